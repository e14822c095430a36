"""One error module: every user-error class is defined in ``flipstudy/errors.py``,
and the CLI's ``main()`` is the one place that catches the family."""
from __future__ import annotations

import ast
import builtins
import importlib
from pathlib import Path

import pytest

import flipstudy.errors as errors
from flipstudy.errors import FlipstudyError
from flipstudy.study.cli import main

ROOT = Path(__file__).resolve().parents[2]
PARTS = ("stimuli", "render", "study", "analysis")
# every built-in exception but KeyboardInterrupt: the CLI's SIGTERM (``Terminated``) is a
# signal raised where Ctrl-C is, not an error
BUILTIN_EXCEPTIONS = {n for n, v in vars(builtins).items()
                      if isinstance(v, type) and issubclass(v, BaseException)} - {"KeyboardInterrupt"}


def package_sources():
    for part in PARTS:
        for p in sorted((ROOT / part).rglob("*.py")):
            yield p, ast.parse(p.read_text(), str(p))


def names_in(node) -> list[str]:
    """The class names an ``except`` clause or a base list names (``a.B`` → ``B``)."""
    if node is None:
        return []
    if isinstance(node, ast.Tuple):
        return [n for e in node.elts for n in names_in(e)]
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Attribute):
        return [node.attr]
    return []


def test_every_exception_class_is_defined_in_errors_py():
    family = set(errors.__all__)
    outside = []
    for p, tree in package_sources():
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                bases = {n for b in node.bases for n in names_in(b)}
                if bases & (family | BUILTIN_EXCEPTIONS):
                    outside.append(f"{p.relative_to(ROOT)}:{node.lineno} class {node.name}")
    assert not outside, "exception classes outside flipstudy/errors.py:\n" + "\n".join(outside)


def test_errors_module_holds_the_whole_family():
    classes = {n: v for n, v in vars(errors).items()
               if isinstance(v, type) and v.__module__ == errors.__name__ and n == v.__name__}
    assert set(classes) == set(errors.__all__)
    assert len(classes) >= 34
    for name, cls in classes.items():
        assert issubclass(cls, FlipstudyError), name
        assert cls.__doc__ and cls.__doc__.strip(), f"{name} has no docstring"
    # the request and conflict errors of the session server are in the family too
    assert issubclass(errors.RequestError, FlipstudyError) and issubclass(errors.ConflictError, FlipstudyError)
    assert errors.RequestError(409, "stored").status == 409


@pytest.mark.parametrize("module, name", [
    ("flipstudy.stimuli.motion", "BVHError"), ("flipstudy.stimuli.synth", "SynthError"),
    ("flipstudy.stimuli.edit.concat", "ConcatError"), ("flipstudy.analysis", "ResponsesError"),
    ("flipstudy.analysis", "NeedsExportError"), ("flipstudy.analysis", "NeedsExport"),
    ("flipstudy.stimuli", "FlipstudyError"),
    ("flipstudy", "BVHError"),
])
def test_package_entry_points_hand_out_the_same_classes(module, name):
    assert getattr(importlib.import_module(module), name) is getattr(errors, name)


def test_every_error_class_is_named_error_and_the_old_names_still_work():
    """Issue 40: each class's name ends in ``Error``; the eleven old names are the same
    classes (``except errors.StudyLocked`` still catches), and a pickle that names a class
    by its old name loads as it."""
    import pickle
    classes = [v for v in vars(errors).values() if isinstance(v, type) and v.__module__ == errors.__name__]
    assert [c.__name__ for c in classes if not c.__name__.endswith("Error")] == []
    assert len(errors.OLD_NAMES) == 11 and not set(errors.OLD_NAMES) & set(errors.__all__)
    for old, cls in errors.OLD_NAMES.items():
        assert cls.__name__ == old + "Error" and getattr(errors, old) is cls
        with pytest.raises(getattr(errors, old)):
            raise cls("x")
        new = pickle.dumps(cls("a message"), protocol=0)
        stored = new.replace(f"\n{cls.__name__}\n".encode(), f"\n{old}\n".encode())
        assert stored != new                                  # the pickle named the old class
        back = pickle.loads(stored)
        assert type(back) is cls and str(back) == "a message"


def test_the_transitional_module_is_gone():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("flipstudy.stimuli.exceptions")


def test_main_is_the_only_place_that_catches_the_family():
    """``except FlipstudyError`` once, in ``main()``."""
    base_catches = []
    for p, tree in package_sources():
        rel = str(p.relative_to(ROOT))
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.ExceptHandler):
                    caught = set(names_in(node.type))
                    if "FlipstudyError" in caught:
                        base_catches.append((rel, fn.name))
    # a nested function would list the handler twice (its own walk and its parent's)
    assert sorted(set(base_catches)) == [("study/cli/__init__.py", "main")], base_catches


def test_a_user_error_is_one_line_and_status_1(tmp_path, capsys):
    """No per-command handler any more: ``main()`` prints the one line each printed."""
    assert main(["status", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err == f"flipstudy status: error: {tmp_path} is not a study folder (no manifest.csv)\n"


def test_needs_export_is_an_error_that_names_the_step(tmp_path, capsys):
    """A study folder without responses.csv (issue 33): "error:", status 1, the export named."""
    assert main(["analyze", str(tmp_path), "--no-figures"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("flipstudy analyze: error: ")
    assert f"flipstudy export {tmp_path} --out" in err and err.count("\n") == 1


def test_a_bad_bvh_is_reported_by_main_with_file_and_line(tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n")
    assert main(["inspect", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"flipstudy inspect: error: {bad}, line 4: ") and err.count("\n") == 1


def test_no_command_of_the_cli_catches_a_user_error_itself():
    """The commands leave every class of :mod:`flipstudy.errors` to ``main()``."""
    family = set(errors.__all__)
    found = []
    for p, tree in package_sources():
        rel = str(p.relative_to(ROOT))
        if not rel.startswith("study/cli/"):
            continue
        for fn in ast.walk(tree):
            if isinstance(fn, ast.FunctionDef) and fn.name != "main":
                for node in ast.walk(fn):
                    if isinstance(node, ast.ExceptHandler) and set(names_in(node.type)) & family:
                        found.append(f"{rel}:{node.lineno} {fn.name}")
    assert not found, "\n".join(found)


def test_a_usage_error_keeps_exit_status_2(capsys):
    """``edit`` with nothing to do: one line, exit 2 (as before it moved below the CLI)."""
    assert main(["edit", "backflip", "--out", "never-written.bvh"]) == 2
    err = capsys.readouterr().err
    assert err == ("flipstudy edit: error: nothing to do: give --flips N, --straighten legs|arms "
                   "or --join OTHER\n")
    assert not Path("never-written.bvh").exists()
