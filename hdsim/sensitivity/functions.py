"""Closed-form test functions with known Sobol' indices (estimator checks).

Each function is a small picklable class: ``f(X)`` takes rows ``(n, d)`` and returns
``(n,)``; ``problem()`` gives its input distribution; ``analytic()`` the exact
first-order, total and (where known) second-order indices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hdsim.errors import unknown_name
from hdsim.sensitivity.problem import Problem, uniform


@dataclass(frozen=True)
class Ishigami:
    """f = sin x1 + a sin² x2 + b x3⁴ sin x1, x ~ U(-π, π)³ (Ishigami & Homma 1990)."""

    a: float = 7.0
    b: float = 0.1

    def __call__(self, X):
        X = np.atleast_2d(X)
        x1, x2, x3 = X[:, 0], X[:, 1], X[:, 2]
        return np.sin(x1) + self.a * np.sin(x2) ** 2 + self.b * x3**4 * np.sin(x1)

    def problem(self) -> Problem:
        return uniform(("x1", "x2", "x3"), [(-math.pi, math.pi)] * 3)

    def analytic(self) -> dict:
        a, b, pi4 = self.a, self.b, math.pi**4
        V1 = 0.5 * (1 + b * pi4 / 5) ** 2
        V2 = a**2 / 8
        V13 = 8 * b**2 * math.pi**8 / 225
        V = a**2 / 8 + b * pi4 / 5 + b**2 * math.pi**8 / 18 + 0.5
        S2 = np.zeros((3, 3))
        S2[0, 2] = V13 / V
        return {"S1": np.array([V1, V2, 0.0]) / V,
                "ST": np.array([V1 + V13, V2, V13]) / V, "S2": S2}


@dataclass(frozen=True)
class GFunction:
    """Sobol' G: f = Π (|4x_i − 2| + a_i)/(1 + a_i), x ~ U(0, 1)^d."""

    a: tuple = (0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0)

    def __call__(self, X):
        X = np.atleast_2d(X)
        a = np.asarray(self.a)
        return np.prod((np.abs(4 * X - 2) + a) / (1 + a), axis=1)

    def problem(self) -> Problem:
        return uniform(tuple(f"x{i + 1}" for i in range(len(self.a))), [(0.0, 1.0)] * len(self.a))

    def analytic(self) -> dict:
        Vi = 1.0 / (3.0 * (1.0 + np.asarray(self.a)) ** 2)
        V = np.prod(1 + Vi) - 1
        ST = np.array([Vi[i] * np.prod(np.delete(1 + Vi, i)) for i in range(len(Vi))]) / V
        return {"S1": Vi / V, "ST": ST, "S2": np.triu(np.outer(Vi, Vi), 1) / V}


@dataclass(frozen=True)
class Linear:
    """y = b0 + Σ b_i x_i with independent inputs: S_i = ST_i = b_i²σ_i² / Σ_j b_j²σ_j².

    The default mixes distributions on purpose (uniform, log-uniform, normal), so the
    analytic check also covers the non-uniform scaling.
    """

    b0: float = 1.0
    coeffs: tuple = (1.0, -2.0, 0.5, 3.0)
    inputs: Problem = field(default_factory=lambda: Problem(
        ("x1", "x2", "x3", "x4"),
        ((0.0, 1.0), (0.0, 1.0), (1.0, 4.0), (0.0, 0.2)),
        ("unif", "unif", "logunif", "norm")))

    def __call__(self, X):
        return self.b0 + np.atleast_2d(X) @ np.asarray(self.coeffs, dtype=float)

    def problem(self) -> Problem:
        return self.inputs

    def analytic(self) -> dict:
        part = np.asarray(self.coeffs, dtype=float) ** 2 * self.inputs.variances()
        S = part / part.sum()
        return {"S1": S, "ST": S.copy(), "S2": np.zeros((len(S), len(S)))}


FUNCTIONS = {"ishigami": Ishigami, "gfunction": GFunction, "linear": Linear}


def get_function(name: str):
    """A closed-form function instance by its CLI name (``ishigami``, ``gfunction``, ``linear``)."""
    try:
        return FUNCTIONS[name]()
    except KeyError:
        raise unknown_name("function", name, FUNCTIONS) from None
