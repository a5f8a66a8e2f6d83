"""The Sobol' index figure says which error bar is which whatever its title: the command
gives its own title (output and N), which had replaced the only words that said it."""

from __future__ import annotations

import numpy as np

from hdsim.plotting import sensitivity


def test_both_intervals_are_in_the_legend_under_a_title_of_the_study(monkeypatch, tmp_path):
    drawn = []
    monkeypatch.setattr(sensitivity, "save_figure", lambda fig, path: drawn.append(fig) or path)
    analysis = {k: np.array([0.3, 0.6]) for k in ("S1", "ST")}
    analysis.update({f"{k}_conf{s}": np.array([0.05, 0.05]) for k in ("S1", "ST") for s in ("", "_replicates")})
    sensitivity.plot_indices(tmp_path / "indices.png", ["a", "b"], analysis, title="K1_Nm_per_rad: N = 64")
    legend = [t.get_text() for t in drawn[0].axes[0].get_legend().get_texts()]
    assert {"bootstrap 95 % CI", "replicate 95 % CI", "first order S1", "total ST"} <= set(legend)
