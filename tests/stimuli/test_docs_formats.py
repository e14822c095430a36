"""The documentation's format tables (docs/_ext/flipstudy_formats.py) are drawn from
the code: every manifest column, response column and design key appears, in the
code's order, with the comment its source line carries."""
import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("docutils", reason="the docs extra (sphinx, docutils) is not installed")

EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "flipstudy_formats.py"


@pytest.fixture(scope="module")
def formats():
    spec = importlib.util.spec_from_file_location("flipstudy_formats", EXT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _names(rows, col=0):
    return [r[col].strip("`") for r in rows]


def test_manifest_table_lists_every_column_in_order(formats):
    from flipstudy.stimuli.contract import EXTRA_COLUMNS, MANIFEST_COLUMNS
    assert _names(formats._rows("manifest")) == list(MANIFEST_COLUMNS)
    assert _names(formats._rows("manifest-ballistic")) == list(EXTRA_COLUMNS)


def test_response_tables_follow_the_export(formats):
    from flipstudy.study import export
    assert _names(formats._rows("responses"), 1) == export.RESPONSE_COLUMNS
    assert _names(formats._rows("participants"), 1) == export.PARTICIPANT_COLUMNS


def test_design_tables_cover_every_key_with_its_default(formats):
    import dataclasses

    from flipstudy.stimuli import design
    rows = {r[0].strip("`"): r for r in formats._rows("design-study")}
    assert list(rows) == list(design.STUDY_FIELDS)
    assert rows["fps"][2] == "`120.0`" and rows["name"][2] == "(required)"
    clips = {r[0].strip("`"): r for r in formats._rows("design-clips")}
    assert list(clips) == [f.name for f in dataclasses.fields(design.ClipSpec)]
    # the meaning is the comment on the field's source line
    assert clips["scale"][3] == "metres per file unit (BVH); None: guess"


def test_unknown_format_names_the_known_ones(formats):
    with pytest.raises(ValueError, match="known: design-study"):
        list(formats._rows("nope"))


def test_error_kinds_table_lists_every_registered_kind(formats):
    from flipstudy.vocab import kinds
    rows = list(formats._rows("error-kinds"))
    assert _names(rows) == [k.name for k in kinds.all_kinds()]
    am = rows[0]
    assert am[2] == "+500 % (excl.), −90 % (excl.)" and "FwP 2007 Table 2" in am[7]
