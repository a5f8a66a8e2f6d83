"""Which evaluator runs a scenario: the dynamic model or the quasi-static one.

A bench may bring a second runner that drops the output inertia (`Setup.quasistatic_runner`,
the locked bench's `hdsim.scenarios.locked.run_locked_quasistatic`) and a criterion that
says when that is allowed (`Setup.quasistatic_criterion`). The user asks for one of

``"dynamic"``
    ``solve_ivp`` on the full model (`hdsim.simulation.path`): the reference, always allowed.
``"quasistatic"``
    The quasi-static evaluator (`hdsim.simulation.quasistatic`), forced; refused on a
    bench that has none.
``"auto"``
    The quasi-static evaluator where the bench's criterion holds, else the dynamic model.

The word is *evaluator*, not *engine*: `hdsim.simulation.quasistatic.locked_twist`
already has an ``engine`` (compiled or numpy loop, ``HDSIM_ENGINE``), which is how the
quasi-static evaluator runs, not whether it is used. docs/sensitivity.md, "Which
evaluator", gives the criterion and the measured agreement.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from hdsim.errors import InputError, unknown_name

#: what a user may ask for
EVALUATORS = ("dynamic", "quasistatic", "auto")


@dataclass(frozen=True)
class EvaluatorChoice:
    """The evaluator a run uses, and why.

    Attributes
    ----------
    requested : str
        What was asked for (`EVALUATORS`).
    chosen : str
        ``"dynamic"`` or ``"quasistatic"``.
    reason : str
        One sentence a user can read in a study's JSON.
    figures : dict
        The numbers the criterion compared (e.g. ``first_period_s``, ``shortest_ramp_s``).
    """

    requested: str
    chosen: str
    reason: str
    figures: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        """JSON-ready form, for run metadata and study files."""
        return asdict(self)


def choose_evaluator(setup, model, scenario, requested: str = "dynamic") -> EvaluatorChoice:
    """The evaluator for ``scenario`` on ``model`` when ``requested`` is asked for.

    Parameters
    ----------
    setup : hdsim.scenarios.setups.Setup
        The scenario's bench.
    model : HarmonicDrive
        The model (single or batch); the criterion is evaluated on it.
    scenario : hdsim.scenarios.scenario.Scenario
        The scenario.
    requested : str
        ``"dynamic"``, ``"quasistatic"`` or ``"auto"``.

    Returns
    -------
    EvaluatorChoice

    Raises
    ------
    InputError
        An unknown evaluator, or ``"quasistatic"`` on a bench without one.
    """
    if requested not in EVALUATORS:
        raise unknown_name("evaluator", requested, EVALUATORS)
    if requested == "dynamic":
        return EvaluatorChoice(requested, "dynamic", "the dynamic model was asked for")
    if setup.quasistatic_runner is None:
        if requested == "quasistatic":
            raise InputError(f"the {setup.name} bench has no quasi-static evaluator; use evaluator "
                             f"'dynamic' or 'auto'")
        return EvaluatorChoice(requested, "dynamic", f"the {setup.name} bench has no quasi-static evaluator")
    holds, reason, figures = setup.quasistatic_criterion(model, scenario)
    if requested == "quasistatic":
        return EvaluatorChoice(requested, "quasistatic",
                               "the quasi-static evaluator was asked for" + ("" if holds else f" ({reason})"),
                               figures)
    return EvaluatorChoice(requested, "quasistatic" if holds else "dynamic", reason, figures)
