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
