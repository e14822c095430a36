"""``flipstudy … | head``: the reader closing the pipe early is not a bug (no traceback,
no "internal error"); the command stops quietly with a shell's SIGPIPE status."""
from __future__ import annotations

import subprocess
import sys


def test_output_into_a_closed_pipe_is_quiet():
    code = ("import sys; from flipstudy.study.cli import main; "
            "sys.exit(main(['inspect', 'backflip', '--json']))")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()                         # the reader leaves before the first line
    err = p.stderr.read().decode()
    status = p.wait(timeout=120)
    assert "internal error" not in err and "Traceback" not in err, err
    assert status == 141, (status, err)
