"""The largest run a scenario may ask for: refused with the estimate and the limit, before
anything is allocated or integrated.

A catalog test is a few seconds of bench time, a few thousand output samples and a few
thousand solver steps (the kinematic-error contract run: 26 s, 26,201 samples, at least
6,987 steps). These bounds are a hundred to a thousand times that, so no honest test is
refused, yet a file with a typo in a duration or a rate (``output_revolutions = 1e6``,
``sample_rate_Hz = 1e9``) is told at once what it would cost instead of exhausting the
machine's memory or running for days.
"""

from __future__ import annotations

from hdsim.errors import InputError

#: output samples of one parameter set (each sample holds ~20 signals and states: 160 B)
MAX_SAMPLES = 5_000_000
#: output samples times parameter sets of one batch (~2 GB of signals)
MAX_BATCH_SAMPLES = 10_000_000
#: bench time [s]
MAX_DURATION_S = 1e5
#: the fewest solver steps the run's step bound allows (at ~1 ms a step of a single
#: model, a quarter of an hour; the kinematic-error contract run needs 7,000)
MAX_SOLVER_STEPS = 1_000_000


def refuse_if_too_large(source: str, *, samples: float, duration: float, batch: int = 1,
                        min_steps: float = 0.0, set_by: str = "") -> None:
    """Raise `InputError` if a run exceeds any limit of this module.

    Parameters
    ----------
    source : str
        Where the scenario came from, for the message.
    samples : float
        Output samples of one parameter set.
    duration : float
        Bench time [s].
    batch : int
        Parameter sets run together.
    min_steps : float
        The fewest solver steps the step bound allows (duration / max_step, summed over
        the run's segments).
    set_by : str
        The scenario keys that set the size, named in the message.

    Raises
    ------
    InputError
        One line with the estimate, the limit and what to change.
    """
    hint = f"; it is set by {set_by}" if set_by else ""
    if not duration <= MAX_DURATION_S:  # also refuses NaN
        raise InputError(f"{source}: the run would last {duration:.3g} s of bench time "
                         f"(limit {MAX_DURATION_S:.0e} s){hint}")
    if not samples <= MAX_SAMPLES:
        raise InputError(f"{source}: the run asks for {samples:.3g} output samples "
                         f"(limit {MAX_SAMPLES:.0e}){hint}")
    if not samples * batch <= MAX_BATCH_SAMPLES:
        raise InputError(f"{source}: {batch} parameter sets of {samples:.3g} output samples each "
                         f"({samples * batch:.3g}, limit {MAX_BATCH_SAMPLES:.0e}) would not fit in memory: "
                         "run smaller batches or sample more coarsely")
    if not min_steps <= MAX_SOLVER_STEPS:
        raise InputError(f"{source}: the run needs at least {min_steps:.3g} solver steps (limit "
                         f"{MAX_SOLVER_STEPS:.0e}, hours of computing){hint} and by solver.max_step")
