"""No function of the package is 80 lines or longer (docstring included): orchestrators stay
short chains of named calls."""

import ast
from pathlib import Path

import mavac

MAX_LINES = 80


def test_every_function_is_shorter_than_80_lines():
    root = Path(mavac.__file__).parent
    too_long = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines >= MAX_LINES:
                    too_long.append(f"{path.relative_to(root.parent)}:{node.lineno} {node.name} ({lines} lines)")
    assert not too_long, "functions of 80 lines or more:\n" + "\n".join(too_long)
