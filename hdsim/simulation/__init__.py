"""Equations of motion and their solution: the elastic path, the locked and driven benches,
the solver, the quasi-static evaluator and linearisation (docs/architecture.md)."""
