"""Radau with block-diagonal linear algebra, for batches of independent parameter sets.

A batch of ``M`` samples with ``n`` states each has a block-diagonal Jacobian. The
stock Radau factorises the whole ``nM × nM`` matrix with SuperLU twice per
Jacobian update (real and complex systems); here each ``n × n`` block is inverted
at once with ``numpy.linalg.inv`` and the solves are one ``einsum``. The
integration formula, error control and step selection are scipy's, untouched.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import Radau


class BlockDiagonalRadau(Radau):
    """``scipy.integrate.Radau`` whose LU and solves use ``block_size × block_size`` blocks.

    Pass as ``solve_ivp(..., method=BlockDiagonalRadau, block_size=n, jac=...)``
    where ``jac`` returns a sparse block-diagonal matrix.
    """

    def __init__(self, fun, t0, y0, t_bound, block_size, **options):
        super().__init__(fun, t0, y0, t_bound, **options)
        n = int(block_size)
        M = self.n // n
        block = np.arange(M)[:, None, None] * n
        rows = (block + np.arange(n)[None, :, None]).repeat(n, axis=2).ravel()
        cols = (block + np.arange(n)[None, None, :]).repeat(n, axis=1).ravel()

        def lu(A):
            self.nlu += 1
            blocks = np.asarray(A.tocsr()[rows, cols]).reshape(M, n, n)
            return np.linalg.inv(blocks)

        def solve_lu(inverse, b):
            return np.einsum("mij,mj->mi", inverse, b.reshape(M, n)).reshape(-1)

        self.lu = lu
        self.solve_lu = solve_lu
