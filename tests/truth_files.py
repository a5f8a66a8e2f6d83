"""The measurement-file contract as the truth generators write it (test support; no hdsim import).

``# key: value`` lines, a header row, and numbers as the shortest text that reads back to
the same float, so a file written here is read back exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["to_csv_text", "write_csv"]


def to_csv_text(columns: dict, meta: dict) -> str:
    """The contract's CSV text: ``# key: value`` lines, a header, exact float rows."""
    lines = [f"# {key}: {value}" for key, value in meta.items()]
    lines.append(",".join(columns))
    table = np.column_stack([np.asarray(v, dtype=float) for v in columns.values()]).tolist()
    lines += [",".join(map(repr, row)) for row in table]  # repr: shortest exact text
    return "\n".join(lines) + "\n"


def write_csv(path, columns: dict, meta: dict) -> Path:
    """Write :func:`to_csv_text` to ``path``; returns the path."""
    path = Path(path)
    path.write_text(to_csv_text(columns, meta), encoding="utf-8")
    return path
