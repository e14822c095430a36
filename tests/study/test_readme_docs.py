"""What a new user reads first agrees with itself (issue 42): getting_started gives
the README's timings and test counts, neither points into ../shared/ (a user does
not have it), `paper/` (the first command's output) is ignored by git, and the
scoring page's code fits the page."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _flat(text: str) -> str:
    return " ".join(text.split())


def test_getting_started_gives_the_readmes_timings_and_test_counts():
    readme = _flat((ROOT / "README.md").read_text(encoding="utf-8"))
    start = _flat((ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8"))
    import re
    # the README's own sentences on the two commands' times, whatever numbers they hold
    claims = [m.group(0) for m in re.finditer(r"[^.]*(?:the whole command took|tests in)[^.]*\.", readme)]
    assert len(claims) >= 2, claims
    for claim in claims:
        assert claim in start, claim
    assert "1,730" not in start and "338 s" not in start


def test_no_page_points_into_the_shared_folder_for_the_design():
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    bad = [str(p.relative_to(ROOT)) for p in pages if "DESIGN.md" in p.read_text(encoding="utf-8")]
    assert not bad


def test_the_first_commands_output_is_ignored_by_git():
    lines = (ROOT / ".gitignore").read_text(encoding="utf-8").splitlines()
    assert "/paper/" in lines or "paper/" in lines


def test_the_scoring_pages_code_lines_fit_the_page():
    text = (ROOT / "docs" / "guide" / "scoring.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```[a-z]*\n(.*?)^```", text, flags=re.S | re.M)
    long = [ln for b in blocks for ln in b.splitlines() if len(ln) >= 80]
    assert blocks and not long, long
