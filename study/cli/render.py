"""The ``render`` and ``figure`` commands of the CLI (:mod:`flipstudy.study.cli`)::

    from flipstudy.study.cli.render import add_commands
    add_commands(subparsers)          # adds `render` and `figure`

``flipstudy render STUDY_DIR [--what video,ghost,trail,strip,composite,overlay]
[--size WxH] [--jobs N] [--video-fps 60] [--style NAME|STYLE.toml] [--frames] [--force] [--quiet]
[--framing clip|stimulus]``
(resumable: only what is missing or stale is made; Ctrl-C stops the workers at once)

``flipstudy figure CLIP [--ghost|--trail|--strip|--composite|--overlay OTHER]
--out FILE.png [--fps F] [--scale S] [--size WxH] [--interval S] [--debug]
[--style NAME|STYLE.toml]``

``--fps`` means one thing in every command: the frame rate of the clip a
command loads (``figure``'s CLIP, overriding a BVH's Frame Time).  The frame
rate of the videos ``render`` writes is ``--video-fps``; ``render --fps`` is
its old spelling, still accepted with a warning.
"""
from __future__ import annotations

import argparse
import sys

from .common import add_clip, add_cluster, add_out, add_study_dir, add_units, reader_options


def _size(text: str):
    from flipstudy.render.study import parse_size
    try:
        return parse_size(text)
    except ValueError as e:                  # parse_size's FlipstudyValueError, as argparse's
        raise argparse.ArgumentTypeError(str(e)) from None


def _style(values):
    """A Style from ``--style`` values: style files (TOML) and at most one
    character style name (ellipsoids, capsules, stick, point-light, mannequin)."""
    if not values:
        return None
    import difflib
    from pathlib import Path

    from flipstudy.render.style import Style
    from flipstudy.stimuli.design import CHARACTER_STYLES
    from flipstudy.errors import FlipstudyValueError
    values = [values] if isinstance(values, str) else list(values)
    names = [v for v in values if v in CHARACTER_STYLES]
    files = [v for v in values if v not in CHARACTER_STYLES]
    if len(names) > 1 or len(files) > 1:
        raise FlipstudyValueError(f"--style: at most one character style and one style file, "
                                  f"got {', '.join(values)}")
    style = Style()
    for f in files:
        if not Path(f).is_file():
            close = difflib.get_close_matches(f, CHARACTER_STYLES, n=1, cutoff=0.5)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise FlipstudyValueError(f"--style {f!r}: neither a character style "
                                      f"({', '.join(CHARACTER_STYLES)}) nor a style file{hint}")
        style = Style.from_toml(f)
    return style.with_character(names[0]) if names else style


class _DeprecatedFps(argparse.Action):
    """``render --fps``, the old spelling of ``--video-fps``: stores the value
    there and says so on stderr."""

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog}: warning: {option_string} is deprecated here (elsewhere --fps is "
              f"a clip's frame rate); use --video-fps", file=sys.stderr)
        setattr(namespace, self.dest, values)


def cmd_render(args) -> int:
    """``flipstudy render``: all stimuli of a study, one camera, in parallel."""
    from flipstudy.render.study import parse_what
    from flipstudy.study.pipeline import render
    res = render(args.study_dir, cluster=args.cluster, what=parse_what(args.what), size=args.size,
                 jobs=args.jobs, fps=args.video_fps, style=_style(args.style), frames=args.frames,
                 progress=not args.quiet, orient=not args.no_orient, force=args.force,
                 framing=args.framing)
    print(res.summary())
    return 0


def cmd_figure(args) -> int:
    """``flipstudy figure``: one still of one clip (ghost, trail, strip, composite, overlay)."""
    from flipstudy.study.motions import figure
    kind = ("overlay" if args.overlay else "trail" if args.trail else "strip" if args.strip
            else "composite" if args.composite else "ghost")
    res = figure(args.clip, args.out, kind=kind, overlay=args.overlay, scale=args.scale, fps=args.fps,
                 readers=reader_options(args),
                 size=args.size, style=_style(args.style), interval=args.interval, debug=args.debug,
                 accept_unphysical=args.accept_unphysical)
    print(res.summary())
    return 0


def add_commands(subparsers) -> None:
    """Add the ``render`` and ``figure`` subcommands to an argparse subparsers
    object; each sets ``func`` (returns an exit code)."""
    p = subparsers.add_parser(
        "render", help="render a study's stimuli (videos, ghosts, trails, strips, composites)",
        description="Render every stimulus of STUDY_DIR/manifest.csv with one style, one camera "
                    "and one take-off spot; outputs and render.json go to STUDY_DIR/render/.")
    add_study_dir(p, "folder with manifest.csv and the stimuli's .bvh")
    p.add_argument("--what", default="video",
                   help="comma-separated outputs: video, ghost, trail, strip, composite, overlay "
                        "(overlay: each stimulus over its clip's reference; default: video)")
    p.add_argument("--size", type=_size, default=(640, 480), metavar="WxH",
                   help="image/video size in pixels (default 640x480; even for video)")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="worker processes (default: number of CPUs); each builds its plotter once")
    p.add_argument("--video-fps", type=float, default=60.0, metavar="FPS",
                   help="frame rate of the videos, in display frames per second; the stimuli are "
                        "resampled to it (default 60)")
    p.add_argument("--fps", dest="video_fps", type=float, action=_DeprecatedFps,
                   default=argparse.SUPPRESS, metavar="FPS",
                   help="deprecated spelling of --video-fps (in the other commands --fps is the "
                        "frame rate of a clip)")
    p.add_argument("--style", metavar="NAME|STYLE.toml", action="append",
                   help="a character style (ellipsoids, capsules, stick, point-light, mannequin; "
                        "a manifest's style column, from the design, comes first) and/or a style "
                        "file of overrides (colours, sizes, ground); may be given twice")
    p.add_argument("--frames", action="store_true", help="also write every video frame as PNG")
    p.add_argument("--no-orient", action="store_true",
                   help="do not turn base clips that travel in other directions to travel like "
                        "the first one (they are only moved to the take-off spot)")
    p.add_argument("--force", action="store_true",
                   help="make every output again (default: only what is missing or stale, i.e. "
                        "made from another stimulus file or with other settings)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--framing", choices=("clip", "stimulus"), default="clip",
                   help="clip (default): one camera per base clip, so the character's size on "
                        "screen is the same in all its stimuli; stimulus: one camera per stimulus, "
                        "each video centred and filling the frame (the size then differs)")
    add_cluster(p)
    p.set_defaults(func=cmd_render)

    f = subparsers.add_parser(
        "figure", help="one still of one clip: ghosts, marker trails, strip, composite, overlay",
        description="Draw one figure of CLIP (a built-in name or a BVH path) in the style of "
                    "Ooi (2016, Chapter 4).")
    add_clip(f)
    g = f.add_mutually_exclusive_group()
    g.add_argument("--ghost", action="store_true", help="ghost copies at the flight's key instants (take-off, apex, landing and between), or every --interval s (default)")
    g.add_argument("--trail", action="store_true", help="marker trails with a legend")
    g.add_argument("--strip", action="store_true", help="animation strip, panels every --interval s")
    g.add_argument("--composite", action="store_true", help="layered frames (first opaque, rest 75 %%)")
    g.add_argument("--overlay", metavar="OTHER", help="overlay CLIP (yellow) and OTHER (turquoise)")
    add_out(f, "FILE.png", "output PNG")
    f.add_argument("--size", type=_size, default=(640, 480), metavar="WxH",
                   help="image size (strip: panel height) in pixels (default 640x480)")
    f.add_argument("--interval", type=float, default=None, metavar="S",
                   help="seconds between copies/panels (default: ghosts at the key instants, others 0.2; strip 0.1)")
    f.add_argument("--debug", action="store_true",
                   help="draw COM and its path, L and velocity arrows, support polygon")
    f.add_argument("--style", metavar="NAME|STYLE.toml", action="append",
                   help="a character style (ellipsoids, capsules, stick, point-light, mannequin) "
                        "and/or a style file of overrides; may be given twice")
    add_units(f)
    f.set_defaults(func=cmd_figure)
