"""The figures: what each one shows, and that they are written whole or not at all."""

import re
from fractions import Fraction

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from PIL import Image

from bouncing_ball import exact
from bouncing_ball.asymptotics import CRITICAL_RESTITUTION, exponents_table
from bouncing_ball.workflow import plotting


@pytest.fixture(scope="module")
def exponents():
    return exponents_table(np.linspace(0.005, 0.995, 199))


def test_fig1_shows_the_jump_of_m_at_one_half(exponents):
    figure = plotting.exponents_figure(exponents, CRITICAL_RESTITUTION)
    axis = figure.axes[0]
    dashed = [line for line in axis.lines if line.get_linestyle() == "--"]
    assert len(dashed) == 2  # m below and above r = 1/2, never joined across the jump
    below, above = (np.asarray(line.get_xdata()) for line in dashed)
    assert below.max() < 0.5 and above.min() == 0.5 and above[1] > 0.5  # joined only to m(1/2) = 1
    assert dashed[1].get_ydata()[0] == 1.0
    assert np.allclose(dashed[0].get_ydata(), 1.5)
    dots = {
        (float(line.get_xdata()[0]), float(line.get_ydata()[0]))
        for line in axis.lines
        if line.get_marker() == "o"
    }
    assert dots == {(0.5, 1.0), (0.5, 1.5)}
    vertical = [
        line for line in axis.lines if np.ptp(line.get_xdata()) == 0 and line.get_marker() != "o"
    ]
    assert vertical[0].get_xdata()[0] == pytest.approx(CRITICAL_RESTITUTION)


def test_fig4_draws_what_it_can_when_a_fit_window_failed():
    speeds = np.geomspace(1e-4, 50, 101)
    edges = np.geomspace(1e-3, 10, 41)
    truth = exact.outgoing_speed_bin_average(edges[:-1], edges[1:], Fraction(1, 2))
    simulated = pd.DataFrame(
        {
            "v_lo": edges[:-1],
            "v_hi": edges[1:],
            "v": np.sqrt(edges[:-1] * edges[1:]),
            "p0v": truth,
            "p0v_err": 0.01 * truth,
            "count": 100,
        }
    )
    rows = []
    for window, names in (
        ("small_speed", ("prefactor", "beta")),
        ("large_speed", ("prefactor", "m", "q")),
    ):
        for name in names:
            value = np.nan if window == "large_speed" else {"prefactor": 1 / 3, "beta": 1.0}[name]
            rows.append(
                {
                    "source": "simulation",
                    "window": window,
                    "fit": "fixed_exponents",
                    "parameter": name,
                    "value": value,
                    "v_min": 1e-3,
                    "v_max": 1e-2,
                }
            )
    panel = {
        "restitution": Fraction(1, 2),
        "simulated": simulated,
        "fits": pd.DataFrame(rows),
        "solver": pd.DataFrame(
            {"v": speeds, "p0v": exact.outgoing_speed_density(speeds, Fraction(1, 2))}
        ),
    }
    axis = plotting.asymptotic_forms_figure([panel]).axes[0]
    labels = [text.get_text() for text in axis.get_legend().get_texts()]
    assert labels[0] == "solver, eq. (inteq)" and "simulation" in labels
    assert any(r"\beta = 1" in label for label in labels) and not any(
        "e^{-qv}" in label for label in labels
    )
    assert axis.get_xscale() == axis.get_yscale() == "log"


def test_fig7_reports_the_mean_squared_residual():
    residuals = pd.DataFrame({"v": [0.1, 1.0, 10.0], "residual": [1.0, -2.0, 0.0]})
    figure = plotting.residuals_figure([(Fraction(1, 4), residuals), (Fraction(3, 5), residuals)])
    texts = [text.get_text() for axis in figure.axes for text in axis.texts]
    assert len(figure.axes) == 2 and r"$\chi^2/n = 1.67$, $n = 3$" in texts[0]
    assert texts[0].startswith("$r = 1/4$") and texts[1].startswith("$r = 3/5$")


def test_figures_are_written_reproducibly_and_atomically(exponents, tmp_path):
    figure = plotting.decay_rate_figure(exponents)
    pdf, png = tmp_path / "fig2.pdf", tmp_path / "fig2.png"
    plotting.save_figure(figure, pdf, png, 60, {"figure": "fig2"})
    first = pdf.read_bytes()
    plotting.save_figure(figure, pdf, png, 60, {"figure": "fig2"})
    assert pdf.read_bytes() == first and png.read_bytes().startswith(b"\x89PNG")

    def broken(path, **options):
        with open(path, "wb") as handle:
            handle.write(b"%PDF-1.4 half a figure")
        raise RuntimeError("disk full")

    figure.savefig = broken
    with pytest.raises(RuntimeError, match="disk full"):
        plotting.save_figure(figure, tmp_path / "new.pdf", tmp_path / "new.png", 60, {})
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fig2.pdf", "fig2.png"]


def test_figures_are_laid_out_once_and_drawn_once_per_format(exponents, tmp_path, monkeypatch):
    """The PNG is the one savefig(bbox_inches="tight") writes, the PDF's page is the PNG's
    box, and the figure is drawn twice in all (no layout draw, no second layout)."""
    with matplotlib.rc_context(plotting.STYLE):
        reference = tmp_path / "reference.png"
        plotting.decay_rate_figure(exponents).savefig(reference, dpi=60)
    draws = []
    draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(draw(self, renderer)))
    pdf, png = tmp_path / "fig2.pdf", tmp_path / "fig2.png"
    plotting.save_figure(plotting.decay_rate_figure(exponents), pdf, png, 60, {"figure": "fig2"})
    assert len(draws) == 2
    written = np.asarray(Image.open(png))
    assert np.array_equal(written, np.asarray(Image.open(reference)))
    page = re.search(rb"/MediaBox \[ 0 0 ([0-9.]+) ([0-9.]+) \]", pdf.read_bytes())
    width, height = float(page[1]), float(page[2])  # points, 72 per inch
    assert width == pytest.approx(written.shape[1] * 72 / 60, abs=72 / 60)
    assert height == pytest.approx(written.shape[0] * 72 / 60, abs=72 / 60)


def test_panel_titles_sit_where_matplotlib_would_place_them():
    figure, axes = plotting.new_figure(1, 2)
    for axis in axes[0]:
        axis.loglog([1e-3, 1e3], [1e-8, 10.0])
    plotting.panel_title(axes[0, 0], "$r = 1/3$")
    with matplotlib.rc_context(plotting.STYLE):
        axes[0, 1].set_title("$r = 1/3$", fontsize=10)  # placed automatically
        figure.draw_without_rendering()
    placed, automatic = (axis.title.get_window_extent().bounds for axis in axes[0])
    assert placed[1:] == pytest.approx(automatic[1:], abs=1e-9)  # same height and size


def test_figs_4_and_5_draw_the_martingale_estimate_never_the_kernel3_one():
    """simulated_bins: p0v_martingale where the table has it, else the plain counts; the
    return-law controlled p0v_controlled (eq. (kernel3)) is never drawn."""
    table = pd.DataFrame(
        {
            "v_lo": [0.1, 1.0],
            "v_hi": [1.0, 10.0],
            "v": [0.3, 3.0],
            "count": [10, 10],
            "p0v": [1.0, 0.1],
            "p0v_err": [0.1, 0.01],
            "p0v_martingale": [1.1, 0.11],
            "p0v_martingale_err": [0.05, 0.005],
            "p0v_controlled": [2.0, 0.2],
            "p0v_controlled_err": [0.01, 0.001],
        }
    )
    assert plotting.simulated_bins(table).p0v.tolist() == [1.1, 0.11]
    plain = table.assign(p0v_martingale=np.nan, p0v_martingale_err=np.nan)
    assert plotting.simulated_bins(plain).p0v.tolist() == [1.0, 0.1]
