"""Sphinx extension: the file formats' reference tables, generated from the code.

A ```` ```{flipstudy-format} NAME ```` block in a MyST (Markdown) page
draws the table of one format from the definitions the code itself uses, so the
documentation cannot drift from what is read and written:

* ``design-study``, ``design-clips``, ``design-groups``, ``design-session`` — the
  design file's keys (:data:`flipstudy.stimuli.design.STUDY_FIELDS` and the fields
  of ``ClipSpec``, ``Group``, ``SessionSettings``);
* ``manifest``, ``manifest-ballistic`` — ``manifest.csv``
  (:data:`flipstudy.stimuli.contract.MANIFEST_COLUMNS`, ``EXTRA_COLUMNS``);
* ``responses``, ``responses-adaptive``, ``participants``, ``simulated-truth`` —
  the exported tables (:mod:`flipstudy.study.export`);
* ``calibration`` — the calibration file's schema (:mod:`flipstudy.stimuli.calibration`).

A field's meaning is the comment on its line in the source (``name: type = default
# meaning``), so the comment the code carries is the one the reader sees.
"""
from __future__ import annotations

import dataclasses
import inspect
import re

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList

_COMMENT = re.compile(r"^\s*(\w+)\s*:\s*[^=#]+?(?:=\s*[^#]*?)?\s*#\s*(.+?)\s*$")


def _comments(cls) -> dict[str, str]:
    """Field name → the comment on its line in ``cls``'s source."""
    out = {}
    for line in inspect.getsource(cls).splitlines():
        m = _COMMENT.match(line)
        if m:
            out.setdefault(m.group(1), m.group(2))
    return out


def _default(f) -> str:
    if f.default is not dataclasses.MISSING:
        return "(required)" if f.default is ... else f"`{f.default!r}`"
    if f.default_factory is not dataclasses.MISSING:
        return "(see below)"
    return "(required)"


def _esc(text: str) -> str:
    return text.replace("|", "\\|").replace("*", "\\*").replace("`", "'")


def _code(text) -> str:
    return f"`{text}`"


def _dataclass_rows(cls, names=None):
    notes = _comments(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for name in names or fields:
        f = fields[name]
        yield [_code(name), _code(f.type).replace("|", "\\|"), _default(f), _esc(notes.get(name, ""))]


def _bounds(k) -> str:
    return ", ".join(f"{'+' if s > 0 else '−'}{top:g} {k.level_unit}" + (" (excl.)" if excl else "")
                     for s, (top, excl) in sorted(k.bounds.items(), reverse=True))


def _kind_rows():
    """One row per registered error kind (flipstudy.vocab.kinds), in registration order."""
    from flipstudy.vocab import kinds
    for k in kinds.all_kinds():
        variants = ", ".join(k.variants) + (" (`profile`)" if k.profiled else "")
        if k.option is not None:
            variants = (variants + "; " if variants else "") + f"`{k.option[0]}`: " + ", ".join(k.option[2])
        injected = k.inject.rsplit(":", 1)[1] if k.injected else "measured only"
        yield [_code(k.name), _esc(k.doc), _bounds(k) if k.bounds else " ", _esc(k.unit), _esc(variants) or " ",
               _esc(injected), _esc("; ".join(k.side_effects)) or " ", _esc(", ".join(k.calibration)) or " "]


def _rows(name):
    from flipstudy.stimuli import contract, design
    from flipstudy.study import export
    if name == "error-kinds":
        yield from _kind_rows()
        return
    if name == "design-study":
        notes = _comments(design.Design)
        for key, (typ, default, _check) in design.STUDY_FIELDS.items():
            d = "(required)" if default is ... else _code(repr(default))
            yield [_code(key), _code(typ.__name__), d, _esc(notes.get(key, ""))]
        return
    if name == "design-clips":
        yield from _dataclass_rows(design.ClipSpec)
        return
    if name == "design-groups":
        yield from _dataclass_rows(design.Group)
        return
    if name == "design-session":
        yield from _dataclass_rows(design.SessionSettings)
        return
    if name == "manifest":
        yield from _dataclass_rows(contract.Stimulus, contract.MANIFEST_COLUMNS)
        return
    if name == "manifest-ballistic":
        yield from _dataclass_rows(contract.Ballistic, contract.EXTRA_COLUMNS)
        return
    cols = {"responses": export.RESPONSE_COLUMNS, "responses-adaptive": export.ADAPTIVE_COLUMNS,
            "participants": export.PARTICIPANT_COLUMNS, "simulated-truth": export.TRUTH_COLUMNS}
    if name in cols:
        for i, c in enumerate(cols[name], 1):
            yield [str(i), _code(c)]
        return
    raise ValueError(f"flipstudy-format: unknown format {name!r}; known: design-study, design-clips, "
                     f"design-groups, design-session, manifest, manifest-ballistic, error-kinds, "
                     f"{', '.join(cols)}, calibration")


_HEADERS = {4: ["key / column", "type", "default", "meaning (from the source)"], 2: ["#", "column"],
            8: ["kind", "what", "levels (design)", "measured in", "variants / option", "injected by",
                "side effects", "calibration sources"]}


class FormatTable(Directive):
    required_arguments = 1
    has_content = False

    def run(self):
        name = self.arguments[0]
        if name == "calibration":
            return self._calibration()
        rows = list(_rows(name))
        header = _HEADERS[len(rows[0])]
        # the pages are MyST Markdown: the table is a Markdown pipe table
        lines = ["| " + " | ".join(header) + " |", "|" + "|".join([":---"] * len(header)) + "|"]
        lines += ["| " + " | ".join(cell or " " for cell in row) + " |" for row in rows]
        return self._parse(lines)

    def _calibration(self):
        from flipstudy.vocab import calibration      # the floor holds the format (stimuli.calibration re-exports it)
        doc = inspect.getdoc(calibration)
        schema = doc.split("Schema::", 1)[1].split("\n\n", 2)[1]
        lines = [f"Format tag `{calibration.FORMAT}`; tasks {', '.join(calibration.TASKS)}.", "",
                 "```text"] + [ln[4:] if ln.startswith("    ") else ln for ln in schema.splitlines()] + ["```"]
        return self._parse(lines)

    def _parse(self, lines):
        node = nodes.container()
        self.state.nested_parse(StringList(lines, source="flipstudy-format"), self.content_offset, node)
        return node.children


def setup(app):
    app.add_directive("flipstudy-format", FormatTable)
    return {"parallel_read_safe": True, "version": "1"}
