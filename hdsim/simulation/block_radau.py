"""Radau with cheaper linear algebra: block-diagonal for batches, straight LAPACK for one model.

A batch of ``M`` samples with ``n`` states each has a block-diagonal Jacobian. The
stock Radau factorises the whole ``nM × nM`` matrix with SuperLU twice per
Jacobian update (real and complex systems); here each ``n × n`` block is inverted
at once with ``numpy.linalg.inv`` and the solves are one ``einsum``.

A single model has a handful of states. There the stock Radau's ``lu_factor`` and
``lu_solve`` spend more time checking and wrapping their arguments than in LAPACK;
`DenseRadau` calls the same LAPACK routines (``getrf``, ``getrs``) directly, so its
steps are the stock ones bit for bit.

In both, the integration formula, error control and step selection are scipy's, untouched.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import Radau
from scipy.linalg import lapack, lu_solve


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


class DenseRadau(Radau):
    """``scipy.integrate.Radau`` whose dense LU and solves call LAPACK's ``getrf``/``getrs``
    directly, as ``scipy.linalg.lu_factor``/``lu_solve`` do after their checks.

    A non-finite matrix is not refused here: the step's error estimate is then not finite,
    the solver fails, and `hdsim.simulation.solver.integrate` says so.
    """

    def __init__(self, fun, t0, y0, t_bound, **options):
        super().__init__(fun, t0, y0, t_bound, **options)
        if not isinstance(self.I, np.ndarray):  # a sparse Jacobian keeps scipy's SuperLU
            return
        real = lapack.get_lapack_funcs(("getrf", "getrs"), dtype=np.float64)
        complex_ = lapack.get_lapack_funcs(("getrf", "getrs"), dtype=np.complex128)

        def lu(A):
            self.nlu += 1
            getrf = (complex_ if np.iscomplexobj(A) else real)[0]
            factors, pivots, _ = getrf(A, overwrite_a=True)
            return factors, pivots

        def solve_lu(LU, b):
            factors, pivots = LU
            if np.iscomplexobj(b) != np.iscomplexobj(factors):  # not a pairing Radau makes
                return lu_solve(LU, b)
            x, _ = (complex_ if np.iscomplexobj(factors) else real)[1](factors, pivots, b, overwrite_b=True)
            return x

        self.lu = lu
        self.solve_lu = solve_lu
