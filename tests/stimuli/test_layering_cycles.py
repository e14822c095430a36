"""No import cycles in the package, not even through a package's ``__init__``.

The graph is built from the source with :mod:`ast`: every ``import`` of every
module, those inside functions too (a function-level import still runs, and a
cycle held together by one still breaks when the order of first use changes).
Relative imports are resolved against the importing module's package, and
``from pkg import name`` points at the submodule ``pkg.name`` when there is one,
else at ``pkg`` itself (its ``__init__``).  A package importing its submodules is
an edge like any other; a submodule's implicit import of its parent package is
not one (Python loads the parent first, whoever imports), but an *explicit*
``from flipstudy.stimuli import builtin`` inside ``flipstudy.stimuli.loading``
is, and closes a cycle when ``flipstudy/stimuli/__init__.py`` imports ``.loading``.
"""
from __future__ import annotations

import ast
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PARTS = ("stimuli", "render", "study", "analysis")


def package_files(root: Path) -> dict[str, Path]:
    """module name → file, for ``flipstudy`` (the root ``__init__.py``), the root
    modules (``errors.py``) and every module of the four parts."""
    files = {"flipstudy": root / "__init__.py"}
    for p in root.glob("*.py"):
        if p.name not in ("__init__.py", "conftest.py"):
            files[f"flipstudy.{p.stem}"] = p
    for part in PARTS:
        for p in (root / part).rglob("*.py"):
            rel = list(p.relative_to(root).with_suffix("").parts)
            if rel[-1] == "__init__":
                rel = rel[:-1]
            files[".".join(["flipstudy", *rel])] = p
    return files


def import_graph(root: Path) -> dict[str, dict[str, int]]:
    """module → {flipstudy module it imports: first line}."""
    files = package_files(root)

    def ours(mod: str) -> str | None:
        while mod and mod not in files:          # `import flipstudy.x.y.attr` → longest module prefix
            mod = mod.rpartition(".")[0]
        return mod or None

    graph = {}
    for name, path in files.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        deps: dict[str, int] = {}
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[:len(base) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                for a in node.names:          # a submodule if there is one, else the package
                    targets.append(f"{mod}.{a.name}" if f"{mod}.{a.name}" in files else mod)
            for t in targets:
                m = ours(t)
                if m and m != name:
                    deps.setdefault(m, node.lineno)
        graph[name] = deps
    return graph


def cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components of more than one module (scipy's)."""
    import numpy as np
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components
    names = sorted(set(graph) | {m for deps in graph.values() for m in deps})
    at = {n: i for i, n in enumerate(names)}
    src = [at[a] for a, deps in graph.items() for b in deps]
    dst = [at[b] for a, deps in graph.items() for b in deps]
    adj = csr_matrix((np.ones(len(src)), (src, dst)), shape=(len(names), len(names)))
    _, label = connected_components(adj, directed=True, connection="strong")
    comps: dict[int, list[str]] = {}
    for n, c in zip(names, label):
        comps.setdefault(int(c), []).append(n)
    return sorted(c for c in comps.values() if len(c) > 1)


def describe(graph, comp: list[str]) -> str:
    inside = set(comp)
    edges = [f"{a} (line {line}) → {b}" for a in comp for b, line in sorted(graph[a].items())
             if b in inside]
    return "import cycle of " + ", ".join(comp) + ":\n  " + "\n  ".join(edges)


def test_no_import_cycles_even_through_an_init():
    g = import_graph(ROOT)
    assert len(g) > 100, "the graph misses the package's modules"
    # every part is reached: the resolver understood the imports
    assert any(m.startswith("flipstudy.render.") for m in g["flipstudy.study.reproduce"])
    found = cycles(g)
    assert not found, "\n".join(describe(g, c) for c in found)


def _copy(tmp_path: Path) -> Path:
    for part in PARTS:
        shutil.copytree(ROOT / part, tmp_path / part, ignore=shutil.ignore_patterns("__pycache__"))
    for p in ROOT.glob("*.py"):
        shutil.copy(p, tmp_path / p.name)
    return tmp_path


def test_the_check_finds_a_cycle_through_a_package_init(tmp_path):
    """The checker itself, on a copy of the tree: a submodule taking a name from its own
    package's ``__init__`` (which imports that submodule) is a cycle."""
    root = _copy(tmp_path)
    init = root / "stimuli" / "__init__.py"
    assert "from .loading import load_clip" in init.read_text()
    f = root / "stimuli" / "loading.py"
    f.write_text(f.read_text() + "\n\ndef _late():\n    from flipstudy.stimuli import builtin\n")
    found = cycles(import_graph(root))
    assert ["flipstudy.stimuli", "flipstudy.stimuli.loading"] in found


def test_the_check_finds_a_cycle_through_relative_and_from_package_imports(tmp_path):
    """``from . import x`` resolves to the submodule ``x``; a three-module ring is found."""
    root = _copy(tmp_path)
    (root / "render" / "ring_a.py").write_text("from . import ring_b\n")
    (root / "render" / "ring_b.py").write_text("def f():\n    from .ring_c import g\n")
    (root / "render" / "ring_c.py").write_text("import flipstudy.render.ring_a.attr\n")
    g = import_graph(root)
    assert g["flipstudy.render.ring_a"] == {"flipstudy.render.ring_b": 1}
    assert ["flipstudy.render.ring_a", "flipstudy.render.ring_b", "flipstudy.render.ring_c"] in cycles(g)
    (root / "render" / "ring_c.py").write_text("import flipstudy.render.style\n")
    assert not any("flipstudy.render.ring_a" in c for c in cycles(import_graph(root)))
