"""Row numbering of a study: replicates, blocks and pieces.

A study of ``N`` base points is ``R`` replicates of ``N / R`` base points, each
base point a block of ``k`` rows (``D + 2``, or ``2D + 2`` with second order).
Global row ``g = r * M + j`` is row ``j`` of replicate ``r``, with
``M = (N / R) * k`` rows per replicate. The first ``n`` base points of a study
(its prefix) are the study at ``n``, because every replicate's design is
extensible.
"""

from __future__ import annotations

import numpy as np

from hdsim.sensitivity.design import block_size, replicate_seed, sample_replicate
from hdsim.sensitivity.problem import Problem

PIECE = 4096  # base points generated, written or checked at a time


class Layout:
    """Geometry of the study ``definition`` at ``n`` base points (no data)."""

    def __init__(self, definition: dict, n: int):
        self.definition, self.n = definition, int(n)

    @property
    def problem(self) -> Problem:
        return Problem.from_dict(self.definition["problem"])

    @property
    def replicates(self) -> int:
        return int(self.definition["replicates"])

    @property
    def k(self) -> int:
        return block_size(self.problem.num_vars, self.definition["second_order"])

    @property
    def rows_per_replicate(self) -> int:
        return self.n // self.replicates * self.k

    @property
    def shape(self) -> tuple[int, int]:
        """Shape of the whole design ``X``."""
        return self.replicates * self.rows_per_replicate, self.problem.num_vars

    def pieces(self, piece: int | None = None):
        """Yield the design piece by piece, so memory stays flat however large N is.

        Parameters
        ----------
        piece : int, optional
            Most base points per piece; default `PIECE`.

        Yields
        ------
        tuple of (int, numpy.ndarray)
            First global row of the piece and its design rows.
        """
        piece = piece or PIECE
        d, k, M = self.definition, self.k, self.rows_per_replicate
        n_r = self.n // self.replicates
        for r in range(self.replicates):
            seed = replicate_seed(d["seed"], r)
            for start in range(0, n_r, piece):
                count = min(piece, n_r - start)
                yield r * M + start * k, sample_replicate(self.problem, count, seed,
                                                          d["second_order"], start)

    def prefix_rows(self, n: int) -> np.ndarray:
        """Global row indices of the first ``n`` base points (split over replicates)."""
        m, M = n // self.replicates * self.k, self.rows_per_replicate
        return (np.arange(self.replicates)[:, None] * M + np.arange(m)[None, :]).reshape(-1)

    def regrid(self, g: int, bigger: "Layout") -> int:
        """Row ``g`` of this layout in a ``bigger`` one (replicates grow in place)."""
        r, j = divmod(int(g), self.rows_per_replicate)
        return r * bigger.rows_per_replicate + j

    def sample_label(self, g: int) -> str:
        """Human name of global row ``g``: replicate, row and block (base point)."""
        r, j = divmod(int(g), self.rows_per_replicate)
        return f"replicate {r} row {j} (block {j // self.k})"


def runs(rows, offsets: bool = False) -> list[tuple]:
    """Split sorted row indices into contiguous runs.

    Parameters
    ----------
    rows : array_like of int
        Sorted row indices.
    offsets : bool
        Also give each run's position in ``rows``.

    Returns
    -------
    list of tuple
        ``(start, stop)`` or, with ``offsets``, ``(start, stop, offset)`` per run.
    """
    rows = np.asarray(rows, dtype=np.int64)
    if not len(rows):
        return []
    cuts = np.flatnonzero(np.diff(rows) != 1) + 1
    starts, stops = np.r_[0, cuts], np.r_[cuts, len(rows)]
    return [(int(rows[a]), int(rows[b - 1]) + 1) + ((int(a),) if offsets else ())
            for a, b in zip(starts, stops)]
