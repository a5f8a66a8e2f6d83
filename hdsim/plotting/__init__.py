"""Figures of runs and studies, drawn with matplotlib's object API.

Every function builds its figure as a `matplotlib.figure.Figure` (or draws into the
axes it is given) and never imports pyplot or selects a backend, so importing or
calling it leaves the backend of the user's process as it was: a notebook keeps its
inline figures, a script its own backend. A returned figure is displayed by a
notebook like any other and saved with `save_figure`.
"""

from __future__ import annotations

from hdsim.io.figures import save_figure

__all__ = ["save_figure", "axes_for"]


def axes_for(ax=None, figsize: tuple[float, float] = (6.4, 4.2)):
    """The figure and axes to draw into: those of ``ax``, or a new one-axes figure.

    Parameters
    ----------
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; None makes a new figure (constrained layout).
    figsize : tuple of float
        Size of a new figure [inch].

    Returns
    -------
    tuple of (matplotlib.figure.Figure, matplotlib.axes.Axes)
        The figure and the axes.
    """
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout="constrained")
        return fig, fig.add_subplot()
    return ax.figure, ax
