"""The one-way flow of DESIGN.md, checked on the source: stimuli → render → study,
stimuli → analysis; the CLI (``flipstudy.study.cli``) sits on top of all four.

Below all four is the floor, ``flipstudy.vocab`` (the folder ``vocab/``, a
sub-package of the root package like the root modules ``errors.py`` and
``results.py``): the study's vocabulary (the error-kind registry, the design, the
stimulus set contract).  Every part may import it; it imports none of them, so
reading a design loads no physics (see docs/reference/layout.md).  It is a
sub-package of the root, not a folder inside ``stimuli/``, because importing any
module of ``flipstudy.stimuli`` runs that package first, and because ``analysis``,
which may not import ``stimuli``, reads the same words.

Every import in every module counts, those inside functions too (a function-level
import is still a dependency, and cycles held together by them are still cycles).
"""
from __future__ import annotations

import ast
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("stimuli", "render", "study", "analysis")
#: the floor below the four parts (the study's vocabulary)
FLOOR = "vocab"
#: what each part (and the floor) may import of the others
ALLOWED = {
    FLOOR: set(),                     # the floor imports no part: no physics
    "stimuli": {FLOOR},
    "render": {"stimuli", FLOOR},
    "analysis": {FLOOR},              # the error family is flipstudy.errors, at the root
    "study": {"stimuli", "render", "analysis", FLOOR},
}


def module_name(root: Path, path: Path) -> str:
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(["flipstudy", *parts])


def imports_of(root: Path, path: Path) -> list[tuple[str, int]]:
    """(absolute module, line) of every import in a module; relative imports resolved."""
    name = module_name(root, path)
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            # `from pkg import sub` may name a submodule
            out += [(f"{mod}.{a.name}", node.lineno) for a in node.names] + [(mod, node.lineno)]
    return out


def graph(root: Path) -> dict[str, dict[str, int]]:
    """module → {imported flipstudy module: line}, for every module of the four parts."""
    files = [p for part in (*PARTS, FLOOR) for p in (root / part).rglob("*.py")]
    names = {module_name(root, p): p for p in files}
    g = {}
    for n, p in names.items():
        deps = {}
        for m, line in imports_of(root, p):
            # the longest prefix that is one of ours
            while m and m not in names:
                m = m.rpartition(".")[0]
            if m and m != n:
                deps.setdefault(m, line)
        g[n] = deps
    return g


def part_of(mod: str) -> str:
    return mod.split(".")[1] if mod.count(".") >= 1 else ""


def violations(root: Path) -> list[str]:
    """Imports against the flow, and import cycles between modules."""
    g = graph(root)
    bad = []
    for n, deps in g.items():
        src = part_of(n)
        for m, line in deps.items():
            dst = part_of(m)
            if dst == src or dst == "":
                continue
            if dst not in ALLOWED[src]:
                bad.append(f"{n} (line {line}) imports {m}: {src} may not import {dst}")
    # cycles: a package importing its own submodules, or a module its parent packages, is
    # how packages work, not a cycle
    def natural(a, b):
        return b.startswith(a + ".") or a.startswith(b + ".")
    edges = {n: [m for m in deps if not natural(n, m)] for n, deps in g.items()}
    index, low, stack, on, sccs = {}, {}, [], set(), []

    def strong(v):
        index[v] = low[v] = len(index)
        stack.append(v); on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                strong(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                sccs.append(sorted(comp))
    for v in sorted(edges):
        if v not in index:
            strong(v)
    bad += [f"import cycle: {' ↔ '.join(c)}" for c in sccs]
    return bad


def test_the_flow_is_one_way_and_acyclic():
    bad = violations(ROOT)
    assert not bad, "\n".join(bad)


def test_the_check_catches_a_render_module_importing_study(tmp_path):
    """The checker itself: a copy of the tree with one forbidden import and one cycle."""
    for part in (*PARTS, FLOOR):
        shutil.copytree(ROOT / part, tmp_path / part, ignore=shutil.ignore_patterns("__pycache__"))
    f = tmp_path / "render" / "style.py"
    f.write_text(f.read_text() + "\n\ndef _late():\n    from flipstudy.study import store\n")
    bad = violations(tmp_path)
    assert any("flipstudy.render.style" in b and "may not import study" in b for b in bad), bad
    g = tmp_path / "stimuli" / "flight.py"
    g.write_text(g.read_text() + "\n\ndef _late():\n    from .analyse import analyse\n")
    assert any(b.startswith("import cycle") and "flipstudy.stimuli.flight" in b
               for b in violations(tmp_path))


def test_installed_distribution_has_one_top_level_name():
    """pyproject maps every package folder into flipstudy and nothing else."""
    import tomllib
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    pkgs = set(cfg["packages"])
    assert {p.split(".")[0] for p in pkgs} == {"flipstudy"}
    on_disk = {module_name(ROOT, p) for part in (*PARTS, FLOOR) for p in (ROOT / part).rglob("__init__.py")}
    assert on_disk | {"flipstudy"} == pkgs, "a package folder is missing from pyproject's list"
    for p, d in cfg["package-dir"].items():
        assert (ROOT / d / "__init__.py").exists(), (p, d)


def test_the_check_catches_the_floor_importing_the_physics(tmp_path):
    """The floor may import no part: a floor module importing stimuli is refused."""
    for part in (*PARTS, FLOOR):
        shutil.copytree(ROOT / part, tmp_path / part, ignore=shutil.ignore_patterns("__pycache__"))
    f = tmp_path / FLOOR / "kinds.py"
    f.write_text(f.read_text() + "\n\ndef _late():\n    from flipstudy.stimuli import physics\n")
    bad = violations(tmp_path)
    assert any("flipstudy.vocab.kinds" in b and "vocab may not import stimuli" in b for b in bad), bad


def test_reading_a_design_imports_no_physics():
    """In a fresh interpreter, reading and checking the paper's design (and a stimulus
    set's rows, and the kind registry) loads no module of the four parts, nor numpy
    or scipy: the vocabulary stands on its own floor."""
    import subprocess
    import sys
    code = ("import sys\n"
            "from flipstudy.vocab.design import PAPER_DESIGN, parse_design\n"
            "from flipstudy.vocab import kinds\n"
            "d = parse_design(PAPER_DESIGN, 'paper.toml')\n"
            "assert len(d.stimulus_names()) == 46 and kinds.get(d.groups[0].kind).variants\n"
            "parts = ('stimuli', 'render', 'study', 'analysis')\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'scipy')\n"
            "             or (m.startswith('flipstudy.') and m.split('.')[1] in parts))\n"
            "print(','.join(bad))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", out.stdout
