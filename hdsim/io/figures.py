"""Write figures atomically: to a temporary file beside the target, then rename.

The one figure writer of the package: the plotting functions, the Sobol' study figures
and the diagnosis report all save through `save_figure`. It only calls
``fig.savefig``, so it works with a `matplotlib.figure.Figure` made without pyplot,
under any backend, and never selects one.
"""

from __future__ import annotations

import os
from pathlib import Path

from hdsim.atomic import atomic_path

__all__ = ["save_figure"]


def save_figure(fig, path: str | os.PathLike, dpi: int = 120, **savefig_options) -> Path:
    """Save a figure atomically; the file format follows the suffix.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        Target file; its suffix (``.png``, ``.svg``, ``.pdf``, ...) gives the format,
        PNG when there is none. Missing folders are created.
    dpi : int
        Resolution of raster formats [dots per inch].
    **savefig_options
        Passed to ``fig.savefig`` (e.g. ``bbox_inches="tight"``).

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png", **savefig_options)
    return path
