"""The ``flipstudy`` command line: one layer over the library.

Each module of this package is one family of commands; each command parses its
options, calls one library function and prints what it did:

* :mod:`.motion` — ``inspect``, ``init``, ``stimuli``, ``archive``, ``edit``
* :mod:`.render` — ``render``, ``figure``
* :mod:`.session` — ``run``, ``status``, ``export``, ``simulate``
* :mod:`.analyze` — ``analyze``
* :mod:`.reproduce` — ``reproduce``
* :mod:`.concat` — ``concat``;  :mod:`.jump` — ``jump``
* :mod:`.web` — ``export-web``, ``import-web``
* :mod:`.plan` — ``plan``
* :mod:`.score` — ``score``, ``calibrate``
* :mod:`.convert` — ``convert``

Heavy libraries (pandas, pyvista, …) are imported by the command that needs them.
"""
from __future__ import annotations

import argparse
import errno
import sys

from .common import load_clip

FAMILIES = ("motion", "render", "session", "analyze", "reproduce", "concat", "jump", "web", "plan",
            "score", "convert")


def build_parser() -> argparse.ArgumentParser:
    import importlib
    ap = argparse.ArgumentParser(prog="flipstudy", description=(
        "Perception studies of ballistic character motion: stimuli, rendering, sessions, analysis."))
    from flipstudy import __version__
    ap.add_argument("--version", action="version", version=f"flipstudy {__version__}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    for family in FAMILIES:
        importlib.import_module(f"{__name__}.{family}").add_commands(sub)
    return ap


def _interrupted(command) -> int:
    """Ctrl-C: one line, the shell's 128 + SIGINT; a further Ctrl-C while the
    interpreter shuts down is ignored (no second traceback, no other status)."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    print(f"flipstudy{' ' + command if command else ''}: interrupted", file=sys.stderr)
    return 130


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``, a scheduler's stop), raised where Ctrl-C raises
    :class:`KeyboardInterrupt`: every clean-up that Ctrl-C runs (workers stopped,
    locks released, staging folders removed) runs for it too."""


def _on_sigterm(signum, frame):
    import signal
    signal.signal(signal.SIGTERM, signal.SIG_IGN)      # a second SIGTERM while cleaning up: ignored
    raise Terminated()


def _terminated(command) -> int:
    """SIGTERM: one line and the shell's 128 + SIGTERM = 143 (what a shell reports for a
    process killed by SIGTERM, so scripts and schedulers see the cause as before)."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    print(f"flipstudy{' ' + command if command else ''}: terminated", file=sys.stderr)
    return 143


#: Exit status of an internal error (a bug): EX_SOFTWARE of BSD's sysexits.h.
EXIT_BUG = 70
#: OSErrors about a file the user named that the machine refused (one line, status 1)
_ENVIRONMENT_ERRNOS = {errno.ENOENT, errno.EACCES, errno.EPERM, errno.ENOSPC, errno.EROFS,
                       errno.EDQUOT, errno.EEXIST, errno.EISDIR, errno.ENOTDIR, errno.ENAMETOOLONG,
                       errno.ELOOP, errno.EBUSY}


def main(argv: list[str] | None = None) -> int:
    """Run one command.  Exit status: 0 done, 1 a user error (a :class:`FlipstudyError`,
    printed in one line naming the file and line or field), 2 a usage error (argparse),
    130 interrupted, 70 (:data:`EXIT_BUG`) anything else: a bug, printed with its
    traceback and a request to report it."""
    try:                                            # the imports take a second or two
        ap = build_parser()
    except KeyboardInterrupt:
        return _interrupted(None)
    args = ap.parse_args(argv)
    if not getattr(args, "func", None):
        ap.print_help()
        return 2
    from flipstudy.errors import FlipstudyError
    import signal
    import threading
    if args.command != "run" and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)  # handled like Ctrl-C (`run`: uvicorn's own)
    try:
        from ..owned import check_outputs
        check_outputs(args.command, args)           # no output path is a study's own file
        import warnings
        with warnings.catch_warnings():             # the package's warnings: one line each
            warnings.showwarning = _warning_line(args.command, warnings.showwarning)
            return args.func(args)
    except Terminated:                              # SIGTERM: one line, 128 + SIGTERM
        return _terminated(args.command)
    except KeyboardInterrupt:                       # Ctrl-C: one line, the shell's 128 + SIGINT
        return _interrupted(args.command)
    except FlipstudyError as e:                     # a user error: one line, no traceback
        print(f"flipstudy {args.command}: {e.label}{e}", file=sys.stderr)
        return e.exit_status
    except BrokenPipeError:                         # the reader left (`| head`): stop quietly
        return _broken_pipe()
    except OSError as e:
        if e.filename is None or e.errno not in _ENVIRONMENT_ERRNOS:
            return _bug(args, e)
        # the machine refused a file the user named (disk full, no permission, read-only, a
        # missing folder): not a bug; one line naming the file
        print(f"flipstudy {args.command}: error: {e.filename}: {e.strerror}", file=sys.stderr)
        return 1
    except Exception as e:                          # a bug: the traceback, and ask for a report
        return _bug(args, e)


def _warning_line(command: str, fallback):
    """A ``warnings.showwarning`` that prints a warning the package raises (a
    UserWarning or FutureWarning from a flipstudy module) as one line,
    ``flipstudy COMMAND: WARNING: message``, and hands any other to ``fallback``."""
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]

    def show(message, category, filename, lineno, file=None, line=None):
        ours = issubclass(category, (UserWarning, FutureWarning)) and \
            Path(filename).resolve().is_relative_to(root)
        if not ours:
            return fallback(message, category, filename, lineno, file, line)
        print(f"flipstudy {command}: WARNING: {message}", file=file or sys.stderr)
    return show


def _broken_pipe() -> int:
    """The program reading our output closed the pipe (``flipstudy … | head``): nothing
    is wrong and nothing more can be said; stdout goes to /dev/null so the interpreter's
    final flush stays quiet, and the status is a shell's for SIGPIPE, 128 + 13."""
    import os
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    return 141


def _bug(args, e: BaseException) -> int:
    """An exception that is not a user error: its traceback and a request to report it."""
    import traceback
    traceback.print_exception(e)
    print(f"flipstudy {args.command}: internal error ({type(e).__name__}): this is a bug in "
          f"flipstudy, not a problem with your input; please report it with the command line "
          f"and the traceback above", file=sys.stderr)
    return EXIT_BUG


if __name__ == "__main__":
    sys.exit(main())
