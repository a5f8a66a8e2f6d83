"""The bench workflow, whole, for every test kind: data checks, fit or diagnosis, outcome,
plausibility against the datasheet, report.

``hdsim fit`` and ``hdsim diagnose`` only parse their arguments and format what these
functions return; from Python the same result comes with everything the command prints::

    import hdsim

    meas = hdsim.load_measurement("bench.csv")
    result = hdsim.diagnose(meas, effects="friction")
    print(result.outcome, result.added, result.next_measurement)
    result.report("diagnosis/")          # index.html with the figures
    json_text = result.to_json()         # exactly what `hdsim diagnose --json` prints

The tutorial ``docs/tutorial-find-missing-effect.md`` walks through it.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path

from hdsim.identification import diagnosis as _builtin_kinds  # noqa: F401  (registers the built-in kinds)
from hdsim.identification.outcome import assess
from hdsim.identification.test_kinds import TestKind, test_kind
from hdsim.io.data_checks import DriveScale, import_checks, unit_checks, wrong_test
from hdsim.io.decimation import thin_record
from hdsim.errors import InputError
from hdsim.io.measurement import Measurement, load_measurement
from hdsim.model.catalog import load_unit

del _builtin_kinds  # imported for the kinds it registers, not used by name

__all__ = ["diagnose", "fit", "BenchDiagnosis", "WrongTest", "examine", "examine_record", "prepare_record",
           "drive_scale", "test_kind"]


def examine(meas: Measurement, scale: DriveScale) -> tuple[list, dict, str]:
    """Every check of a record before a fit: (checks, data summary, wrong-test sentence or '').

    The checks are the import's (`hdsim.io.data_checks.import_checks`), what the kind's
    `TestKind.prepare` changed, the thinning of a long log (`hdsim.io.decimation`), and
    the record's test kind's (`TestKind.checks`). The data summary holds ``rows`` (those
    fitted), ``dropped_rows``, ``logged_rows`` for a thinned log, and the kind's figures
    (noise floors, reversals, loading rates, speeds …).
    """
    return _examine(meas, scale)[1:]


def _examine(meas: Measurement, scale: DriveScale) -> tuple:
    """(the prepared record, checks, data summary, wrong-test sentence): `examine`, keeping
    the record the kind prepared, so that what is fitted is prepared once."""
    kind = test_kind(meas.test)
    meas, turned = kind.prepare(meas)
    imported = import_checks(meas) + unit_checks(meas, scale)
    logged = len(meas)
    meas, thinned = thin_record(meas) if kind.thinnable else (meas, [])  # a long log: one row in k
    checks, figures = kind.checks(meas, scale)
    checks = imported + list(turned) + thinned + list(checks)
    data = {"rows": len(meas), "dropped_rows": meas.rows.dropped_rows, **figures}
    if thinned:
        data["logged_rows"] = logged
    return meas, checks, data, wrong_test(checks)


def examine_record(meas: Measurement, unit=None) -> tuple[list[dict], dict, str, DriveScale]:
    """(checks as JSON objects, data summary, wrong-test sentence or '', the drive's
    `hdsim.io.data_checks.DriveScale`) of a record against the named drive (`examine`)."""
    return prepare_record(meas, unit)[1:]


def drive_scale(unit=None) -> DriveScale:
    """The datasheet numbers of ``unit`` (a name, a drive file, a `HarmonicDrive`, or the
    default unit) that the checks and the plausibility compare a record with."""
    return DriveScale.of(unit if unit is not None and not isinstance(unit, str) else load_unit(unit))


def prepare_record(meas: Measurement, unit=None) -> tuple:
    """(the record in its kind's conventions, then what `examine_record` gives): the one
    place a record is prepared and checked before a fit or a diagnosis."""
    scale = drive_scale(unit)
    meas, checks, data, wrong = _examine(meas, scale)
    return meas, [c.to_json() for c in checks], data, wrong, scale


@dataclass
class BenchDiagnosis:
    """A finished diagnosis with what the record allows to conclude from it.

    Attributes
    ----------
    diagnosis : hdsim.identification.engine.Diagnosis
        The rounds, candidates and fits.
    outcome : str
        ``found``, ``improved``, ``nothing_missing`` or ``cannot_decide``
        (`hdsim.identification.outcome`).
    next_measurement : str
        What to record so that the record can decide ('' when nothing more is needed).
    checks : list of dict
        The data checks and the plausibility of the final fit against the datasheet.
    data : dict
        The data summary of the checks (rows, noise floors, reversals, loading rates).
    summary : dict
        The engine's JSON of the diagnosis, made once (the outcome is judged on it).

    Everything else (``added``, ``ranking``, ``steps``, ``final`` …) is the engine's result's.
    """

    diagnosis: object
    kind: TestKind
    outcome: str
    next_measurement: str
    checks: list
    data: dict
    scale: DriveScale
    summary: dict
    report_path: Path | None = None

    def __getattr__(self, name):
        if name == "diagnosis":  # not set yet (a copy or an unpickled object being built): no endless recursion
            raise AttributeError(name)
        return getattr(self.diagnosis, name)

    def to_json(self) -> dict:
        """The object ``hdsim diagnose --json`` prints (docs/cli.md)."""
        out = copy.deepcopy(self.summary)  # a caller may change what it gets
        out.update(outcome=self.outcome, next_measurement=self.next_measurement, checks=list(self.checks),
                   data=dict(self.data))
        if self.report_path is not None:
            out["report"] = str(self.report_path)
        return out

    def report(self, directory) -> Path:
        """Write the report (``index.html``, ``index.md`` and the figures) into ``directory``
        (InputError when it is a file, `TestKind.report_folder`)."""
        directory = self.kind.report_folder(directory)
        self.report_path = Path(self.kind.write_report(self.diagnosis, directory, self.to_json(), self.scale))
        return self.report_path


@dataclass
class WrongTest:
    """A record that is not the test it claims: nothing is fitted, the checks say what it looks like."""

    measurement: Measurement
    reason: str
    checks: list
    data: dict
    outcome: str = "wrong_test"
    next_measurement: str = ""
    added: list = field(default_factory=list)
    ranking: list = field(default_factory=list)
    report_path: Path | None = None

    def to_json(self) -> dict:
        out = {"test": self.measurement.test, "outcome": self.outcome, "checks": list(self.checks),
               "data": dict(self.data), "next_measurement": "", "baseline": None, "ranking": [], "added": [],
               "final": None, "ambiguous": [], "verdict": f"not a {self.measurement.test} test: {self.reason}"}
        if self.report_path is not None:
            out["report"] = str(self.report_path)
        return out

    def report(self, directory) -> Path:
        """Write a page that says why nothing was fitted (``index.html`` and ``index.md``)."""
        from hdsim.identification.report_page import wrong_test_page

        self.report_path = wrong_test_page(self.measurement, TestKind.report_folder(directory), self.to_json())
        return self.report_path


def diagnose(measurement: Measurement, effects=None, *, unit=None, families=None, candidates: dict | None = None,
             max_rounds: int | None = None, max_steps: int | None = None, log=None):
    """Check a record, find the effect families it needs beyond ``effects``, and say what
    the record allows to conclude.

    Parameters
    ----------
    measurement : Measurement
        From `hdsim.load_measurement`, of any registered test kind.
    effects : str, list or dict, optional
        The families the model already has (the baseline).
    unit : str or HarmonicDrive, optional
        The drive (default: the catalog default); its datasheet is the plausibility reference.
    families, candidates, max_rounds, max_steps, log
        As for `hdsim.identification.diagnosis.diagnose`.

    Returns
    -------
    BenchDiagnosis or WrongTest
        ``.outcome``, ``.checks``, ``.next_measurement``, ``.added``, ``.ranking``,
        ``.to_json()`` and ``.report(directory)``; a `WrongTest` (outcome
        ``wrong_test``) when the record is not the test it claims.
    """
    measurement, kind = _record(measurement, effects, families)
    prepared, checks, data, wrong, scale = prepare_record(measurement, unit)
    if wrong:
        return WrongTest(measurement, wrong, checks, data)
    result = kind.diagnose(prepared, effects, unit=unit, families=families, candidates=candidates,
                           max_rounds=max_rounds, max_steps=max_steps, log=log)
    summary = result.to_json()
    outcome, next_measurement = assess(summary, data, kind)
    checks = checks + kind.plausibility(result.final.fit, scale)
    return BenchDiagnosis(result, kind, outcome, next_measurement, checks, data, scale, summary)


def fit(measurement: Measurement, effects=None, *, unit=None):
    """Check a record and fit the model with ``effects`` to it, for any test kind.

    The record goes through the checks `diagnose` runs (a long log is thinned, a record
    that is not the test it claims is refused) before it is fitted.

    Returns the kind's fit result (`hdsim.identification.fit.FitResult` for the twist
    tests, `hdsim.identification.running_fit.RunningFit` for a running-torque sweep); its
    ``.drive`` is the `HarmonicDrive` carrying everything fitted, which `run_scenario`
    and `sobol` take as it is; ``.checks`` are the data checks and the plausibility of the
    fitted values against the datasheet (JSON objects, as ``hdsim fit --json`` prints them)
    and ``.data`` the data summary.

    Raises
    ------
    InputError
        A record that is not the test it claims (the sentence of the failed check), not a
        record at all, or ``effects`` naming a family the test does not know.
    """
    measurement, kind = _record(measurement, effects)
    prepared, checks, data, wrong, scale = prepare_record(measurement, unit)
    if wrong:
        raise InputError(f"{measurement.source}: this is not a {measurement.test} test: {wrong}")
    result = kind.fit(prepared, effects, unit=unit)
    result.checks = checks + kind.plausibility(result, scale)
    result.data = data
    return result


def _record(measurement, *effects) -> tuple[Measurement, TestKind]:
    """A record (a `Measurement` as it is, a path read with `load_measurement`'s defaults) and
    its test kind; a misnamed family in ``effects`` is refused before the record is examined."""
    if isinstance(measurement, (str, os.PathLike)):
        measurement = load_measurement(measurement)
    elif not isinstance(measurement, Measurement):
        raise InputError(f"expected a measurement (hdsim.load_measurement(path)) or a file path, "
                         f"got {type(measurement).__name__}")
    kind = test_kind(measurement.test)
    for names in effects:
        kind.baseline_effects(names)
    return measurement, kind
