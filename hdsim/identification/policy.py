"""What a diagnosis does after a round: add, change a form, stand in, or stop.

`decide_round` is the whole policy of a round as one pure function of the scored
candidates: it fits nothing, reads no record and changes nothing, so every rule can be
checked on hand-built candidate lists (``tests/test_policy.py``). The loop that fits the
candidates and applies the decision is `hdsim.identification.engine`; the reasoning behind
each rule is in the module text of `hdsim.identification.diagnosis` and in
``docs/tutorial-find-missing-effect.md``.

A candidate here is anything with ``family``, ``effect``, ``score`` (lower is better),
``accepted`` (it passed its test kind's acceptance rule) and ``holdout_gain`` (one gain
per hold-out fold); the running-torque test's candidates also carry ``share`` (the share
of the residual above the noise floor they remove), by which its ties are judged.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Thresholds", "RoundState", "Decision", "decide_round", "wants_other_forms", "rate_ambiguity",
           "rate_question_left", "explains_as_well"]


@dataclass(frozen=True)
class Thresholds:
    """The acceptance and tie thresholds of one test kind (each kind names its own set).

    Attributes
    ----------
    score : float
        Evidence: a candidate's score (ΔBIC with the effective sample size) must fall
        below this.
    holdout_gain : float
        Hold-out prediction error must fall by at least this fraction.
    floor_holdout_gain : float
        ... by this once the residual is at its noise floor: a family can then only
        remove the little structure left, and a proxy of an imperfect form removes a few
        per cent of it.
    strong_holdout_gain : float
        A hold-out gain this large on *both* folds stands for the score: a model far from
        the record leaves a strongly correlated residual whose few effective samples make
        the score timid.
    min_gain : float
        The rms error on all rows must fall by at least this fraction (0: not asked).
    min_share : float
        The candidate must remove at least this share of the residual variance above the
        noise floor (0: not asked).
    proxy_holdout_gain : float
        Hold-out gain still needed once the families in the model may take other shapes
        of their own (0: not asked).
    tie_fraction, tie_floor : float
        Near tie: the runner-up's score within max(``tie_floor``, ``tie_fraction``·|best|).
    tie_share : float or None
        When set, ties are judged by ``share`` instead: two candidates whose shares differ
        by less than this (a torque residual's share is the comparable figure across
        families whose parameter counts differ).
    shape_margin, shape_floor : float
        At one loading rate, the two families of a rate pair are told apart by the loop's
        shape only when their scores differ by more than max(``shape_floor``,
        ``shape_margin``·|best|).
    """

    score: float = -10.0
    holdout_gain: float = 0.05
    floor_holdout_gain: float = 0.10
    strong_holdout_gain: float = 0.10
    min_gain: float = 0.0
    min_share: float = 0.0
    proxy_holdout_gain: float = 0.0
    tie_fraction: float = 0.10
    tie_floor: float = 10.0
    tie_share: float | None = None
    shape_margin: float = 0.25
    shape_floor: float = 20.0

    def near_tie(self, best, rival) -> bool:
        """Whether ``rival`` explains the residual too nearly as well as ``best`` to call."""
        if self.tie_share is not None:
            return abs(rival.share - best.share) < self.tie_share
        return abs(rival.score - best.score) < max(self.tie_floor, self.tie_fraction * abs(best.score))


@dataclass(frozen=True)
class RoundState:
    """What the policy needs to know of the diagnosis so far.

    Attributes
    ----------
    round_no : int
        The round being decided (1 is the first, against the baseline).
    current : mapping
        Family -> effect id of the model the candidates were scored against.
    added : tuple of str
        Families added so far.
    reshaped : tuple of str
        Families whose form has changed so far (each changes once at most).
    residual_explained : bool
        The current model's residual is white or at its noise floor.
    one_rate : bool
        The record holds one loading rate, so a rate pair cannot be told apart by the rate.
    rate_partner : callable
        Family -> the family one loading rate cannot tell it from ('' for none).
    separating : callable
        ``(family, family) -> str``: the measurement that separates two families.
    """

    round_no: int
    current: Mapping[str, str]
    added: tuple = ()
    reshaped: tuple = ()
    residual_explained: bool = False
    one_rate: bool = False
    rate_partner: Callable[[str], str] = field(default=lambda family: "")
    separating: Callable[[str, str], str] = field(default=lambda a, b: "")

    @property
    def on_baseline(self) -> bool:
        """Still the user's baseline (nothing added, no form changed) with a residual left."""
        return not self.added and not self.reshaped and not self.residual_explained


@dataclass(frozen=True)
class Decision:
    """The outcome of a round.

    ``action`` is one of ``"add"`` (``chosen`` enters the model as a new family),
    ``"reshape"`` (``chosen`` is a family of the model in another form, taken instead of
    any addition), ``"stand_in"`` (``chosen`` enters the model, not added: one loading
    rate cannot name its rate law, and the families that do not hinge on it are tried
    against a model with the loss; ``pair`` is the pair left undecided) or ``"stop"``.
    ``ambiguous`` holds the entries this round reports, in the ``ambiguous`` format of
    the diagnosis JSON.
    """

    action: str
    chosen: object | None = None
    ambiguous: tuple = ()
    pair: tuple = ()


def wants_other_forms(ranked: list, has_other_forms: bool, state: RoundState) -> bool:
    """Whether the families in the model are refitted in their other forms this round.

    When a candidate passes (the proxy guard: an imperfect shape of a family in the
    model leaves a residual that another family absorbs in part), and, while nothing has
    been added nor changed and a residual is left, also when none passes: the user names
    families, not forms, and the form of a named family may hide the missing one.
    """
    return has_other_forms and (any(c.accepted for c in ranked) or state.on_baseline)


def decide_round(ranked: list, reshapes: list | None, state: RoundState, thresholds: Thresholds) -> Decision:
    """Decide a round from its scored candidates.

    Parameters
    ----------
    ranked : list
        One candidate per family tried, in any order.
    reshapes : list or None
        The families of the model refitted in their other forms (None: not tried).
    state : RoundState
        The diagnosis so far.
    thresholds : Thresholds
        The test kind's tie rule.

    Returns
    -------
    Decision
    """
    ranked = sorted(ranked, key=lambda c: c.score)
    # the best score among the candidates that pass: a better score whose hold-out
    # predictions fail is an over-fit, and it must not hide a runner-up that passes
    passing = [c for c in ranked if c.accepted]
    best = passing[0] if passing else None
    notes = []
    if reshapes:
        ordered = sorted(reshapes, key=lambda c: c.score)
        if best is None:  # nothing to add: the best form that passes is taken, if any
            form = next((c for c in ordered if c.accepted), None)
            changes = form is not None
        elif ordered[0].accepted and thresholds.near_tie(best, ordered[0]):
            # too close to call: the family is added (a new effect is the more useful lead
            # for the bench), the other form named with the measurement that separates them
            form, changes = ordered[0], False
            notes.append(_tie_entry(best, form, state, other_form={form.family: form.effect}))
        else:
            form = ordered[0]
            changes = form.accepted and form.score < best.score
        if changes:
            return Decision("reshape", form, tuple(notes))
    if best is None:
        # a loss that explains part of what is left, beside its partner, but too little to
        # be added: at one rate that is the pair's question, not "nothing more"
        pair = rate_question_left(ranked, state, thresholds) if state.one_rate else None
        if pair:
            notes.append(_pair_entry(pair, ranked, state))
        return Decision("stop", None, tuple(notes), tuple(pair or ()))
    pair = rate_ambiguity(best, ranked, state, thresholds) if state.one_rate else None
    if pair:
        # one loading rate cannot say whether this loss grows with the rate: the pair is
        # reported with the measurement that separates it, and neither is added
        notes.append(_pair_entry(pair, ranked, state))
        if set(pair) & set(state.current):
            return Decision("stop", None, tuple(notes), pair)  # the loss in the model is the question
        # a loss is missing and only its rate law is undecidable: it stands in the model
        # while the families that do not hinge on the rate are tried (a gap behind a
        # one-rate friction is invisible until the loss is in)
        return Decision("stand_in", best, tuple(notes), pair)
    if len(passing) > 1 and thresholds.near_tie(best, passing[1]):
        notes.append(_tie_entry(best, passing[1], state))
    return Decision("add", best, tuple(notes))


def rate_ambiguity(best, ranked: list, state: RoundState, thresholds: Thresholds) -> tuple | None:
    """The rate pair of ``best`` when one loading rate cannot separate it, else None.

    One family of the pair is a loss that grows with the rate (damping), the other one
    that does not (friction); at one rate only the loop's shape tells them apart, and an
    imperfect friction form leaves a shape that damping mimics. So: when the best
    candidate is of a pair and its partner is already in the model, or is a candidate
    that also explains the residual within the shape margin of the best, the record
    cannot decide between them.
    """
    partner = state.rate_partner(best.family)
    rival = next((c for c in ranked if c.family == partner), None)
    if partner and (partner in state.current
                    or rival is not None and explains_as_well(best.score, rival.score, thresholds)):
        return tuple(sorted((best.family, partner)))
    return None


def rate_question_left(ranked: list, state: RoundState, thresholds: Thresholds) -> tuple | None:
    """The rate pair when, at one loading rate, nothing passes yet a loss is left.

    The family best scored of all belongs to a rate pair whose partner is already in the
    model, and it explains part of the residual: evidence (score below the threshold) and
    a better prediction of *both* hold-out folds, only too little of it to be added (the
    gain floors). One rate cannot say whether that loss grows with the rate or is the
    partner's own shape, so the pair is reported with the second rate that separates
    them instead of a silent "nothing more" (zoo: a damping at 3x the noise beside a
    LuGre friction at one rate, score -96, hold-out gain 5 %).
    """
    if not ranked:
        return None
    top = min(ranked, key=lambda c: c.score)  # one that could not be fitted scores +inf: never a question
    partner = state.rate_partner(top.family)
    if not partner or partner not in state.current:
        return None
    predicts = len(top.holdout_gain) == 2 and min(top.holdout_gain) > 0.0
    return tuple(sorted((top.family, partner))) if top.score < thresholds.score and predicts else None


def explains_as_well(best_score, rival_score, thresholds: Thresholds):
    """The rival also explains the residual (score below the threshold) within
    max(``shape_floor``, ``shape_margin``·|best|) of the best score (numpy-vectorised)."""
    return (rival_score < thresholds.score) & (
        rival_score - best_score < np.maximum(thresholds.shape_floor, thresholds.shape_margin * np.abs(best_score)))


def _tie_entry(best, rival, state: RoundState, **extra) -> dict:
    """The ``ambiguous`` entry of a near tie in which ``best`` is added."""
    return {"families": [best.family, rival.family], "scores": [best.score, rival.score],
            "round": state.round_no, "measurement": state.separating(best.family, rival.family),
            "added": True, **extra}


def _pair_entry(pair, ranked: list, state: RoundState) -> dict:
    """The ``ambiguous`` entry of a rate pair one loading rate cannot separate (neither added)."""
    by_family = {c.family: c.score for c in ranked}
    return {"families": list(pair), "scores": [by_family.get(f) for f in pair], "round": state.round_no,
            "measurement": state.separating(*pair), "added": False}
