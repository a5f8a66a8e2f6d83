"""``hdsim compliance``: the flexspline's torsional compliance by segment, optionally with FE."""

from __future__ import annotations

from hdsim.cli import _common, emit_json
from hdsim.model.catalog import load_unit
from hdsim.model.fe_check import CUP_SEGMENTS, compliance_report

LABELS = {"diaphragm": "diaphragm", "end_radius": "end radius R_k", "cylinder": "cylinder h_c",
          "lead_radius": "lead radius R_v", "undercut": "undercut h_p", "cup": "cup (the above)",
          "rim": "toothed rim h_pz", "mesh_zone": "mesh zone (calibrated)", "total": "total"}


def register(subparsers) -> None:
    """Add the ``compliance`` verb."""
    p = subparsers.add_parser(
        "compliance", help="torsional compliance of the flexspline by segment",
        description="The torsional compliance of the flexspline by segment from the closed forms; "
                    "with --fe, the cup and the rim on the balls also by finite elements "
                    "(needs scikit-fem: pip install 'hdsim[fe]').")
    p.add_argument("--unit", default=None,
                   help="built-in unit (default CSG-25-100; see 'hdsim units') or a drive file")
    p.add_argument("--fe", action="store_true",
                   help="also check the cup and the rim by finite elements (a few seconds)")
    _common.add_set_argument(p, help="change a parameter (SI units), e.g. flexspline.h_c=0.7e-3")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=main)


def main(args) -> int:
    """Print the compliance by segment; exit status."""
    model, _ = _common.apply_sets(load_unit(args.unit), None, _common.parse_sets(args.sets))
    report = compliance_report(model, fe=args.fe)
    if args.json:
        emit_json(report)
        return 0
    closed = report["closed_form"]
    print(f"torsional compliance of {report['unit']} (kappa_mesh = {report['calibration']['kappa_mesh']:.4g})")
    print(f"  {'segment':<24} {'C [rad/(N·m)]':>14} {'K [N·m/rad]':>12} {'share':>7}")
    for name, label in LABELS.items():
        value = closed[name]
        share = "" if name == "cup" else f"{100.0 * value / closed['total']:6.1f}%"
        indent = "    " if name in CUP_SEGMENTS else "  "
        print(f"{indent}{label:<{26 - len(indent)}} {value:14.4g} {1.0 / value:12.4g} {share:>7}")
    if "fe" in report:
        fe = report["fe"]
        print(f"  cup by finite elements:  {fe['cup']:.4g} rad/(N·m), {fe['ratio']:.4f} × the closed form "
              f"({fe['elements']} elements, last refinement changed it by {100 * fe['change']:.2g} %, "
              f"{fe['seconds']:.2g} s)")
        rim = fe["rim_radial"]
        print(f"  rim on the balls, radial: {rim['fe']:.4g} N/m per zone by finite elements, "
              f"{rim['ratio']:.4f} × the closed form ({rim['closed_form']:.4g} N/m)")
    return 0
