"""The one progress bar of the long commands (flipstudy.stimuli._progress)."""
import io
import re

from flipstudy.stimuli._progress import Progress


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_non_tty_gets_one_summary_line():
    out = io.StringIO()
    bar = Progress(3, "stimuli", stream=out)
    for name in ("a", "b", "c"):
        bar.step(name)
    bar.close()                                   # a second close adds nothing
    assert re.fullmatch(r"stimuli: 3/3 in \d+\.\d s\n", out.getvalue())


def test_quiet_writes_nothing():
    for stream in (io.StringIO(), _Tty()):
        bar = Progress(2, "render", enabled=False, stream=stream)
        bar.step("x")
        bar.step("y")
        bar.close()
        assert stream.getvalue() == ""


def test_tty_gets_a_tqdm_bar_that_ends_the_line():
    out = _Tty()
    bar = Progress(2, "render", stream=out)
    bar.step("first")
    bar.step("second")
    text = out.getvalue()
    assert "render" in text and "2/2" in text and "second" in text and text.endswith("\n")
    assert not re.search(r"render: 2/2 in", text)


def test_closed_early_the_summary_says_how_far_it_got():
    out = io.StringIO()
    bar = Progress(5, "participants", stream=out)
    bar.step("sim001")
    bar.close()
    assert out.getvalue().startswith("participants: 1/5 in ")


def test_non_tty_gets_periodic_lines_with_the_count_and_the_last_piece():
    """Issue 33: a log, a notebook or CI hears from a long render now and then."""
    out = io.StringIO()
    bar = Progress(4, "render", stream=out, every=0.0)
    for name in ("a", "b", "c", "d"):
        bar.step(name)
    lines = out.getvalue().splitlines()
    assert [ln.split(" (")[0] for ln in lines[:3]] == ["render: 1/4", "render: 2/4", "render: 3/4"]
    assert "(last: c)" in lines[2] and "s left" in lines[2]
    assert re.fullmatch(r"render: 4/4 in \d+\.\d s", lines[3])


def test_a_heartbeat_speaks_in_a_log_until_the_step_ends_and_not_on_a_terminal():
    import time
    from flipstudy.stimuli._progress import Heartbeat
    out = io.StringIO()
    with Heartbeat("analyze", stream=out, every=0.01):
        deadline = time.monotonic() + 10
        while "still working" not in out.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
    n = out.getvalue().count("\n")
    assert n >= 1 and out.getvalue().startswith("analyze: still working, ")
    time.sleep(0.05)
    assert out.getvalue().count("\n") == n          # stopped with the step
    tty = _Tty()
    with Heartbeat("plan", stream=tty, every=0.01):
        time.sleep(0.05)
    assert tty.getvalue() == ""
