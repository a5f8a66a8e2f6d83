"""Lines of a package folder at a commit: all lines, and lines that hold code (docstrings,
comments and blank lines excluded), file by file.

    python validation/code_lines.py hdsim/identification            # the working tree
    python validation/code_lines.py hdsim/identification f365e79    # a commit
"""

from __future__ import annotations

import argparse
import ast
import io
import subprocess
import tokenize
from pathlib import Path

SKIPPED = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}


def code_lines(source: str) -> int:
    """Lines holding a token that is neither a comment nor a docstring."""
    docstrings = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                docstrings.update(range(first.lineno, first.end_lineno + 1))
    lines = set()
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type not in SKIPPED:
            lines.update(n for n in range(token.start[0], token.end[0] + 1) if n not in docstrings)
    return len(lines)


def sources(folder: str, commit: str | None) -> dict[str, str]:
    if commit is None:
        return {str(p): p.read_text(encoding="utf-8") for p in sorted(Path(folder).glob("*.py"))}
    names = subprocess.run(["git", "ls-tree", "--name-only", commit, folder + "/"], capture_output=True,
                           text=True, check=True).stdout.split()
    return {n: subprocess.run(["git", "show", f"{commit}:{n}"], capture_output=True, text=True, check=True).stdout
            for n in sorted(names) if n.endswith(".py")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("commit", nargs="?")
    args = parser.parse_args()
    total = [0, 0]
    for name, text in sources(args.folder.rstrip("/"), args.commit).items():
        lines, code = len(text.splitlines()), code_lines(text)
        total[0] += lines
        total[1] += code
        print(f"{lines:6d} {code:6d}  {name}")
    print(f"{total[0]:6d} {total[1]:6d}  all lines, code lines")


if __name__ == "__main__":
    main()
