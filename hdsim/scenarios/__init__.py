"""Scenario files, one Setup per bench (schema, runner, metrics), runs and run files."""
