"""Every public name has a numpydoc docstring whose examples run.

The public names are the stable entry points (``flipstudy.__init__``) and each
part's ``__all__``.  A function or class passes when its docstring has a numpydoc
``Examples`` section with ``>>>`` lines and, when it takes arguments, a
``Parameters`` section.  The examples run as doctests in the default test run
(``--doctest-modules`` over the package, see pyproject.toml).  Module-level
constants cannot carry a docstring of their own in Python; they are documented by
the ``#:`` comment above them and are not checked here.

Names not yet documented would be listed in ``KNOWN_GAP`` (empty now); the list
may only shrink: a name that gains its docstring must leave it, and no new public
name may join it.
"""
import importlib
import inspect
import re

STABLE = ("load_bvh", "save_bvh", "builtin", "analyse", "Clip", "Body", "FlipstudyError")
PARTS = ("flipstudy.stimuli", "flipstudy.render", "flipstudy.study", "flipstudy.analysis")

# the names still without a numpydoc docstring with examples (issue 35); may only shrink.
# Empty: every public function and class is documented; a new public name needs its docstring.
KNOWN_GAP: set[str] = set()

#: the sub-packages, whose ``__all__`` names are public too (issue 40)
SUBPACKAGES = ("flipstudy.stimuli.motion", "flipstudy.stimuli.edit", "flipstudy.stimuli.edit.concat",
               "flipstudy.stimuli.control", "flipstudy.stimuli.synth", "flipstudy.study.web")
# their names still without a numpydoc docstring with examples; may only shrink.
# Empty: every public function and class of the sub-packages is documented (issue 40 item 5);
# a new public name needs its docstring.
KNOWN_SUB_GAP: set[str] = set()


def public_names(parts=PARTS, stable=STABLE) -> dict[str, object]:
    """``module.name`` → object, for every function and class of the public API
    (``parts``: the packages whose ``__all__`` is read)."""
    out = {}
    root = importlib.import_module("flipstudy")
    for n in stable:
        out[f"flipstudy.{n}"] = getattr(root, n)
    for part in parts:
        mod = importlib.import_module(part)
        for n in getattr(mod, "__all__", ()):
            obj = getattr(mod, n)
            if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.isbuiltin(obj):
                out[f"{part}.{n}"] = obj
    return out


def _section(doc: str, title: str) -> str | None:
    """The text of a numpydoc section (``Title`` over a line of dashes), or None."""
    m = re.search(rf"^{title}\n-{{{len(title)}}}\n(.*?)(?=^\w[\w ]*\n-{{3,}}\n|\Z)", doc, re.M | re.S)
    return m.group(1) if m else None


def _takes_arguments(obj) -> bool:
    target = obj.__init__ if inspect.isclass(obj) else obj
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return False            # an exception takes its message
    try:
        params = inspect.signature(target).parameters
    except (TypeError, ValueError):
        return False
    return any(p not in ("self", "args", "kwargs") for p in params)


def problems(obj) -> list[str]:
    doc = inspect.getdoc(obj) or ""
    out = []
    ex = _section(doc, "Examples")
    if ex is None or ">>>" not in ex:
        out.append("no Examples section with >>> lines")
    if _takes_arguments(obj) and _section(doc, "Parameters") is None and _section(doc, "Attributes") is None:
        out.append("no Parameters section")
    return out


def test_section_parser_finds_what_numpydoc_calls_sections():
    def f(x):
        """Do.

        Parameters
        ----------
        x : int
            A number.

        Examples
        --------
        >>> f(1)
        """
    assert problems(f) == []

    def g(x):
        """Do.

        >>> g(1)
        """
    assert problems(g) == ["no Examples section with >>> lines", "no Parameters section"]


def test_every_public_name_has_a_numpydoc_docstring_with_examples():
    missing = {name: p for name, obj in public_names().items() if (p := problems(obj))}
    new = sorted(set(missing) - KNOWN_GAP)
    assert not new, "public names without a numpydoc docstring with Examples:\n" + "\n".join(
        f"  {n}: {'; '.join(missing[n])}" for n in new)
    fixed = sorted(KNOWN_GAP - set(missing))
    assert not fixed, f"documented now, remove from KNOWN_GAP: {fixed}"


def test_every_public_name_of_the_subpackages_has_a_numpydoc_docstring_with_examples():
    missing = {name: p for name, obj in public_names(SUBPACKAGES, ()).items() if (p := problems(obj))}
    new = sorted(set(missing) - KNOWN_SUB_GAP)
    assert not new, "public names without a numpydoc docstring with Examples:\n" + "\n".join(
        f"  {n}: {'; '.join(missing[n])}" for n in new)
    fixed = sorted(KNOWN_SUB_GAP - set(missing))
    assert not fixed, f"documented now, remove from KNOWN_SUB_GAP: {fixed}"
