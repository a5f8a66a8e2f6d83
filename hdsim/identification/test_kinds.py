"""Test kinds: what each bench test brings to the one identification engine.

A test kind is registered once, the way effects are (`register_test_kind`), and
everything that differs between tests comes from it: the families it can show and the
class that holds each family's knowledge (rate partner, the measurement that separates
two families), its fit, its session (how a candidate is fitted, scored and held out),
its acceptance thresholds, its plausibility checks against the datasheet, what keeps a
record from deciding, its report, and its error unit. The engine
(`hdsim.identification.engine`), the policy (`hdsim.identification.policy`) and the
workflow (`hdsim.identification.workflow`) ask the kind and never the test's name.

The built-in kinds are ``stiffness`` and ``kinematic_error``
(`hdsim.identification.diagnosis`) and ``running_torque``
(`hdsim.identification.running_diagnosis`). A user's kind derives from `TestKind`,
declares the measurement columns it reads (``columns``) and is registered; see
``docs/architecture.md`` and ``tests/test_test_kind_plugin.py`` for one written in a
test file and diagnosed end to end.

A session (`TestKind.session`) is the kind's state for one record. The engine reads:
``measurement``, ``chosen`` (family -> effect id of the baseline), ``one_rate``,
``fold_rule``, ``passes``, and calls ``baseline()``, ``entry_forms(family)``,
``try_models(step, trials, residual)``, ``other_forms(current, done)``,
``confidence(steps)`` and ``findings(step)``; a step's residual is judged by the kind's
``residual_whiteness``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import ClassVar

from hdsim.atomic import check_writable_folder
from hdsim.errors import InputError, unknown_name
from hdsim.identification.engine import run_diagnosis
from hdsim.identification.policy import Thresholds
from hdsim.io.measurement_checks import register_test_columns, unregister_test_columns
from hdsim.io.report_files import REPORT_PAGES
from hdsim.model.family import FamilyKnowledge

__all__ = ["TestKind", "FamilyKnowledge", "register_test_kind", "unregister_test_kind", "test_kind", "test_kinds"]

#: test name -> registered kind
_KINDS: dict[str, "TestKind"] = {}


class TestKind:
    """Base of the test kinds: the defaults every kind may keep."""

    __test__ = False  # not a pytest test class, whatever its name says

    #: the ``# test:`` name of the records this kind reads
    name: ClassVar[str] = ""
    #: unit of the fit error, and its JSON key
    error_unit: ClassVar[str] = "rad"
    error_key: ClassVar[str] = "rmse_rad"
    #: the unit the report shows errors in, and its factor from ``error_unit``
    report_unit: ClassVar[tuple[str, float]] = ("rad", 1.0)
    #: the acceptance and tie thresholds of this kind
    thresholds: ClassVar[Thresholds] = Thresholds()
    #: the fits run faster with numba's compiled evaluator (``pip install 'hdsim[fast]'``)
    compiled_fits: ClassVar[bool] = False
    #: the engine stops before a round when the residual is white
    stop_when_white: ClassVar[bool] = True
    #: measurement columns: required, and optional (for a kind the file reader does not know)
    columns: ClassVar[tuple[str, ...]] = ()
    optional_columns: ClassVar[tuple[str, ...]] = ()

    # ------------------------------------------------------------------ families
    def families(self) -> Mapping[str, type]:
        """Family -> the class holding its knowledge (``rate_partner``, ``separated_by`` …),
        in the order a model lists them; every family the test can show."""
        raise NotImplementedError

    def ordered(self, current: Mapping[str, str]) -> list[str]:
        """The families of ``current`` in the kind's order."""
        return [f for f in self.families() if f in current]

    def rate_partner(self, family: str) -> str:
        """The family one loading rate cannot tell ``family`` from ('' for none)."""
        cls = self.families().get(family)
        return cls.rate_partner if cls is not None else ""

    def rate_dependent(self, family: str) -> bool:
        cls = self.families().get(family)
        return cls is not None and cls.rate_dependent

    def separating(self, a: str, b: str) -> str:
        """The measurement that separates families ``a`` and ``b`` (each pair written once,
        on either family's class, or a family's ``separated_from_any``)."""
        known = self.families()
        for one, other in ((a, b), (b, a)):
            cls = known.get(one)
            text = cls and (cls.separated_by.get(other) or cls.separated_from_any)
            if text:
                return text
        return "a test at another loading rate and amplitude"

    def keeps_entry(self, entry: dict, kept: list) -> bool:
        """Whether an ambiguous entry is reported beside those already ``kept``."""
        return True

    # ------------------------------------------------------------------ fitting
    def parse_effects(self, effects):
        """The baseline's families from the user's text, list or dict."""
        raise NotImplementedError

    def baseline_effects(self, effects) -> dict:
        """`parse_effects` with every family checked, whatever form ``effects`` takes (text,
        list or dict): a family of another test is refused as one this test cannot show
        (`cannot_show`), a name no test knows with its close matches."""
        known = self.families()
        others = {f for kind in _KINDS.values() for f in kind.families()} | set(known)
        try:
            chosen = self.parse_effects(effects)
        except InputError:
            shown = next((name for name in _names(effects) if name in others and name not in known), None)
            if shown is not None:
                raise self.cannot_show(shown) from None
            raise
        for family in chosen:
            if family not in known:
                raise self.cannot_show(family) if family in others else unknown_name("effect family", family, others)
        return chosen

    def cannot_show(self, family: str) -> InputError:
        """The refusal of a family this test cannot show (another test's)."""
        return InputError(f"a {self.name} test cannot show the {family} family; it shows {', '.join(self.families())}")

    def fit(self, meas, effects=None, *, unit=None):
        """The model with ``effects`` fitted to ``meas`` (a result with ``.summary()``)."""
        raise NotImplementedError

    def fit_summary(self, result, stem, scale) -> dict:
        """What ``hdsim fit --json`` prints of ``result`` (``stem``: the path, less its suffix,
        beside which figures of the fit may be written)."""
        return result.summary()

    def session(self, meas, chosen, *, unit=None, candidates=None, max_steps=None):
        """The kind's state for one record (see the module text)."""
        raise NotImplementedError

    def diagnose(self, meas, effects=None, *, unit=None, families=None, candidates=None,
                 max_rounds=None, max_steps=None, log=None):
        """Greedy forward selection of the families ``meas`` needs beyond ``effects``."""
        chosen = self.baseline_effects(effects)
        # the kind's names, checked as the baseline's are (a form's id names its family)
        pool = list(self.baseline_effects(families)) if families is not None else list(self.families())
        session = self.session(meas, chosen, unit=unit, candidates=candidates, max_steps=max_steps)
        return run_diagnosis(self, session, pool, max_rounds=max_rounds, log=log)

    # ------------------------------------------------------------------ reporting
    def fit_errors(self, fit) -> dict:
        """The fit's error figures under the kind's keys (rms first)."""
        raise NotImplementedError

    def fit_json(self, fit) -> dict:
        """What the diagnosis JSON's ``final`` says of the fitted model beside its errors."""
        return {}

    def step_figures(self, step) -> dict:
        """Figures of a step for the before/after table beside its errors."""
        return {}

    def diagnosis_json(self, diagnosis) -> dict:
        """Keys the kind adds to the diagnosis JSON."""
        return {}

    def verdict(self, whiteness: dict) -> str:
        if whiteness["explained"]:
            return (f"explained: the residual is at the noise level "
                    f"(rms {whiteness['rms_over_noise']:.2f}× the noise floor)")
        return (f"residual not white (Ljung-Box p = {whiteness['p_value']:.2g}, rms "
                f"{whiteness['rms_over_noise']:.1f}× the noise floor): the model still misses an effect "
                "that no family in the library explains, or explains only in part; this is not a success")

    def residual_whiteness(self, fit) -> dict:
        """What `verdict` reads of ``fit``'s residual (`hdsim.identification.residuals.whiteness`):
        for a fit's page, which has no diagnosis to ask."""
        from hdsim.identification.residuals import whiteness

        return whiteness(fit.residual)

    def prepare(self, meas) -> tuple[object, list]:
        """The record in the kind's conventions, and the checks that say what was changed
        (none by default); `hdsim.fit` and `hdsim.diagnose` fit the record it returns."""
        return meas, []

    def checks(self, meas, scale) -> tuple[list, dict]:
        """The model-free checks of a record (`hdsim.io.data_checks.Check`) and the figures
        of its data summary (none by default)."""
        return [], {}

    def plausibility(self, fit, scale) -> list[dict]:
        """Fitted values against the datasheet, as checks (none by default)."""
        return []

    def limits(self, diagnosis_json: dict, data: dict, ranking: list) -> list[str]:
        """What kept the record from deciding, each as the measurement that would."""
        return [pair["measurement"] for pair in diagnosis_json.get("ambiguous", []) if pair.get("measurement")]

    def unexplained(self) -> str:
        """What to record when the residual keeps a structure no family explains."""
        return ("the residual keeps a structure that no family of the library explains on this record: look "
                "at the residual against time in the report")

    def report_figures(self, diagnosis, folder, scale) -> list:
        """The kind's figures of a diagnosis report, drawn into ``folder``: [(path, caption)]
        (``scale``: the drive's datasheet numbers). The residual against time and the error
        of every step are drawn for every kind."""
        return []

    def fit_figures(self, result, folder, scale) -> list:
        """The kind's figures of a fit's page (``hdsim fit --report``), drawn into ``folder``:
        [(path, caption)] (the residual against time is drawn for every kind)."""
        return []

    def report_sections(self, diagnosis, diagnosis_json: dict) -> list:
        """The kind's tables of a diagnosis report: [(heading, (head, rows))]."""
        return []

    def fit_sections(self, result, summary: dict) -> list:
        """The kind's tables of a fit's page (``summary``: what ``hdsim fit --json`` prints of
        ``result``): [(heading, (head, rows))]."""
        return []

    #: the heading of a report's fitted-parameter table (a torque test names its shaft)
    parameters_heading: ClassVar[str] = "Fitted parameters"
    #: a long log of this test may keep one row in k (`hdsim.io.decimation`): its content is
    #: slow against the logging rate, which the noise check confirms row by row
    thinnable: ClassVar[bool] = True

    def parameter_unit(self, result, name: str) -> str:
        """The unit of a fitted parameter of ``result`` for the report's table: the fitted
        model's own (`HarmonicDrive.param_info`), "" where it has none."""
        try:
            return result.model.param_info(name).get("unit", "")
        except (AttributeError, InputError):
            return ""

    def predictions(self, result, scale) -> list:
        """What the fitted drive predicts for the maker's tests, each with a 95 % band
        (`hdsim.identification.predictions.Prediction`), for the report pages (``scale``:
        the drive's datasheet numbers); none here."""
        return []

    @staticmethod
    def report_folder(directory) -> Path:
        """``directory`` as the folder a report is written into (made when it is written),
        checked before anything is drawn: InputError in one line when it is a file, cannot be
        written into, or holds a folder where the report's page goes."""
        folder = Path(directory)
        if folder.exists() and not folder.is_dir():
            raise InputError(f"{folder} is a file, not a folder; give a folder for the report (it is created if "
                             "missing)")
        check_writable_folder(folder)
        for name in REPORT_PAGES:
            if (folder / name).is_dir():
                raise InputError(f"{folder / name} is a folder, so the report cannot be written there; remove it "
                                 "or give another folder")
        return folder

    def write_report(self, diagnosis, directory, summary: dict, scale):
        """Write the report page of ``diagnosis`` into ``directory`` (``summary``: its JSON;
        ``scale``: the drive's datasheet numbers); returns the page's path."""
        from hdsim.identification.report_page import diagnosis_page  # matplotlib only when asked

        return diagnosis_page(diagnosis, directory, summary, scale)


def _names(effects) -> list[str]:
    """The family or effect names of ``effects`` as the user wrote them (text, list or dict)."""
    items = effects.split(",") if isinstance(effects, str) else list(effects or ())
    return [str(item).partition("=")[0].strip() for item in items]


def register_test_kind(kind: TestKind) -> TestKind:
    """Make ``kind`` the one that reads records of its test name (a kind registered again
    under the same name replaces it). Its columns are told to the file reader when it
    names them.

    Raises
    ------
    InputError
        A kind without a name.
    """
    if not kind.name:
        raise InputError(f"{type(kind).__name__} needs a test name")
    if kind.columns:
        register_test_columns(kind.name, kind.columns, kind.optional_columns)
    _KINDS[kind.name] = kind
    return kind


def unregister_test_kind(name: str) -> None:
    """Remove a kind registered with `register_test_kind` (and its columns)."""
    kind = _KINDS.pop(name, None)
    if kind is not None and kind.columns:
        unregister_test_columns(name)


def test_kind(name: str) -> TestKind:
    """The kind registered for the test ``name``; InputError with the known names."""
    if name not in _KINDS:
        raise unknown_name("test", name, _KINDS)
    return _KINDS[name]


def test_kinds() -> dict[str, TestKind]:
    """Every registered kind by test name."""
    return dict(_KINDS)


test_kind.__test__ = False  # a function pytest must not collect when a test module imports it
test_kinds.__test__ = False
