"""The flexspline's compliance by segment, with a finite-element second opinion for the cup.

`compliance_report` is what ``hdsim compliance`` prints: the closed-form chain of
`hdsim.model.drive.compliance_chain` segment by segment, the cup (everything between
the hub and the toothed rim) and, on request, two finite-element checks (scikit-fem,
the ``fe`` extra): the cup in torsion on the flexspline's meridional section
(`hdsim.physics.fe_cup`) and the rim's radial stiffness on the wave-generator balls
(`hdsim.physics.fe_rim`). See docs/physics.md, section 3.7.
"""

from __future__ import annotations

import itertools

import numpy as np

from hdsim.errors import InputError
from hdsim.model.drive import HarmonicDrive, radial_support
from hdsim.model.geometry import FlexsplineGeometry

#: the segments between the hub and the toothed rim, in the order the torque meets them
CUP_SEGMENTS = ("diaphragm", "end_radius", "cylinder", "lead_radius", "undercut")


def cup_section(g: FlexsplineGeometry) -> dict[str, float]:
    """The dimensions the finite-element cup is meshed from [m, Pa] (one geometry, not a batch).

    Parameters
    ----------
    g : FlexsplineGeometry
        The geometry.

    Returns
    -------
    dict
        Keyword arguments of `hdsim.physics.fe_cup.cup_torsion_fe`.

    Raises
    ------
    InputError
        For a batch of geometries.
    """
    values = dict(r_hub=g.r_hub, t_d=g.t_d, R_k=g.R_k, R_i=g.R_i, h_c=g.h_c, h_pz=g.h_pz, h_p=g.h_p,
                  R_v=g.R_v, cylinder_length=g.cylinder_length, undercut_width=g.undercut_width, G=g.G)
    if any(np.ndim(v) for v in values.values()):
        raise InputError("the finite-element cup takes one geometry, not a batch")
    return {k: float(v) for k, v in values.items()}


def corner_shapes(model: HarmonicDrive, names, spread: float = 0.10) -> list[HarmonicDrive]:
    """The model at every corner of the box ``(1 ± spread)·nominal`` of the named flexspline
    dimensions (``2**len(names)`` shapes), where a check of the closed forms is hardest.

    Parameters
    ----------
    model : HarmonicDrive
        One unit.
    names : iterable of str
        Flexspline dimensions, e.g. ``("h_pz", "h_c", "R_v", "R_k", "h_p")``.
    spread : float
        Half-width of the box as a share of the nominal value [-].

    Returns
    -------
    list of HarmonicDrive
        One model per corner.
    """
    nominal = {name: model.params()[f"flexspline.{name}"] for name in names}
    return [model.with_updates({f"flexspline.{k}": f * v for (k, v), f in zip(nominal.items(), corner)})
            for corner in itertools.product((1.0 - spread, 1.0 + spread), repeat=len(nominal))]


def fe_cup_compliance(g: FlexsplineGeometry, *, tolerance: float = 0.005):
    """Torsional compliance of the cup by finite elements, refined until converged.

    Parameters
    ----------
    g : FlexsplineGeometry
        One geometry.
    tolerance : float
        Relative change between two refinements that counts as converged [-].

    Returns
    -------
    hdsim.physics.fe_cup.FEResult
        Compliance [rad/(N·m)], element count, solve time [s] and the last change.

    Raises
    ------
    InputError
        Without scikit-fem (install ``hdsim[fe]``), or for a batch of geometries.
    SolverError
        If the compliance has not converged at the finest refinement.
    """
    from hdsim.physics.fe_cup import converged_cup_compliance

    return converged_cup_compliance(**cup_section(g), tolerance=tolerance)


def fe_rim_stiffness(model: HarmonicDrive, *, refinement: float = 2.0) -> float:
    """Radial stiffness of the rim on the balls per engagement zone by finite elements [N/m].

    The mean of a ball on the zone centre and two balls straddling it (the wave
    generator turns, so the balls pass every position), with the unit's support width;
    refinement 2 reads about 1 % stiff (docs/physics.md §3.7).

    Parameters
    ----------
    model : HarmonicDrive
        One unit.
    refinement : float
        Mesh density factor of `hdsim.physics.fe_rim.rim_radial_stiffness_fe` [-].

    Returns
    -------
    float
        Stiffness [N/m], to compare with ``radial_support(...).rim``.

    Raises
    ------
    InputError
        Without scikit-fem, or for a batch of geometries.
    """
    from hdsim.physics.fe_rim import rim_radial_stiffness_fe

    g, wg = model.geometry, model.wave_generator
    values = dict(bore_radius=g.R_i, wall=g.h_pz, face_width=g.face_width, E=g.E, nu=g.nu,
                  arc_length=radial_support(g, wg).zone_arc, contact_width=wg.support_width)
    if any(np.ndim(v) for v in values.values()) or np.ndim(wg.balls):
        raise InputError("the finite-element rim takes one geometry, not a batch")
    args = {k: float(v) for k, v in values.items()}
    args.update(balls=int(round(float(wg.balls))), refinement=refinement)
    return float(np.mean([rim_radial_stiffness_fe(**args, ball_on_centre=centre).stiffness
                          for centre in (True, False)]))


def closed_form_cup(model: HarmonicDrive) -> float:
    """The cup of the closed-form chain: the segments from the diaphragm to the undercut
    [rad/(N·m)]."""
    chain = model.compliance()
    return float(sum(np.asarray(getattr(chain, name)) for name in CUP_SEGMENTS))


def fe_cup_check(model: HarmonicDrive) -> dict:
    """The finite-element cup against the closed-form one.

    Parameters
    ----------
    model : HarmonicDrive
        One unit.

    Returns
    -------
    dict
        ``cup`` [rad/(N·m)], ``elements``, ``seconds``, ``change`` (the last refinement's
        relative change) and ``ratio`` (FE cup over `closed_form_cup`).
    """
    result = fe_cup_compliance(model.geometry)
    return {"cup": result.compliance, "elements": result.elements, "seconds": round(result.seconds, 3),
            "change": result.change, "ratio": result.compliance / closed_form_cup(model)}


def compliance_report(model: HarmonicDrive, *, fe: bool = False) -> dict:
    """The torsional compliance of the flexspline by segment [rad/(N·m)].

    Parameters
    ----------
    model : HarmonicDrive
        One unit (its calibration is applied to the mesh zone).
    fe : bool
        Also the two finite-element checks (needs scikit-fem).

    Returns
    -------
    dict
        ``unit``; ``closed_form``: the segments, ``cup``, ``rim``, ``mesh_zone`` (calibrated)
        and ``total``; ``calibration``: ``kappa_mesh``; with ``fe``, ``fe``: `fe_cup_check`
        and ``rim_radial``: the rim's radial stiffness per zone [N/m] by FE (``fe``) and
        closed form (``closed_form``) and their ``ratio``.
    """
    chain = {k: float(np.asarray(v)) for k, v in model.compliance().as_dict().items()}
    closed = {name: chain[name] for name in CUP_SEGMENTS}
    closed["cup"] = sum(closed.values())
    closed.update(rim=chain["rim"], mesh_zone=chain["mesh_zone"], total=sum(chain.values()))
    report = {"unit": model.name, "closed_form": closed,
              "calibration": {"kappa_mesh": float(np.asarray(model.calibration.kappa_mesh))}}
    if fe:
        rim_closed = float(np.asarray(radial_support(model.geometry, model.wave_generator).rim))
        try:
            cup = fe_cup_check(model)  # first: its mesh grows with a thin wall, and a refusal comes before any solve
            rim_fe = fe_rim_stiffness(model)
            report["fe"] = {**cup, "rim_radial": {"fe": rim_fe, "closed_form": rim_closed, "ratio": rim_fe / rim_closed}}
        except InputError as exc:  # the closed forms took this drive; say that only the FE check objects
            raise InputError(f"the finite-element check refuses this drive, which the closed forms accept "
                             f"(run without --fe for them): {exc}") from None
    return report
