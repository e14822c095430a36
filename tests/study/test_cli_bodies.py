"""The CLI is a thin layer: every command's body (its ``cmd_*`` or ``handler``
function, docstring left out) parses options, calls one library function and
prints its result, in at most 25 lines (issue 29)."""
from __future__ import annotations

import ast
from pathlib import Path

CLI = Path(__file__).resolve().parents[2] / "study" / "cli"
MAX_LINES = 25


def command_bodies():
    for p in sorted(CLI.glob("*.py")):
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, ast.FunctionDef) and (node.name.startswith("cmd_") or node.name == "handler"):
                body = node.body
                if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                    body = body[1:]
                yield f"{p.name}:{node.name}", body[-1].end_lineno - body[0].lineno + 1


def test_every_command_body_is_short():
    bodies = dict(command_bodies())
    assert len(bodies) >= 20, sorted(bodies)             # the commands were found
    long = {k: n for k, n in bodies.items() if n > MAX_LINES}
    assert not long, f"command bodies over {MAX_LINES} lines (move the work into the library): {long}"
