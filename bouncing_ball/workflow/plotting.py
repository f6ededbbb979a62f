"""The figures: pure functions from the workflow's tables to matplotlib Figures.

One function per figure of the paper (Figs. 1-5) and one per figure past it (Figs.
6-12); `save_figure` writes PDF and PNG atomically.  No pyplot state: each
function builds its own ``Figure``, so the scripts can run side by side.
"""

import json
import logging

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.ticker import NullLocator  # noqa: E402

from .. import __version__  # noqa: E402
from ..restitution import exact_string  # noqa: E402
from .io import atomic_paths  # noqa: E402

STYLE = {
    "font.family": "serif",
    "mathtext.fontset": "cm",
    "font.size": 9,
    "axes.labelsize": 10,
    "legend.fontsize": 7.5,
    "legend.frameon": False,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "lines.linewidth": 1.2,
    "errorbar.capsize": 0,
    "savefig.bbox": "tight",
}

SIMULATION_MARKERS = ("o", "s", "^", "D", "v", "<", ">", "p", "h", "*")


def restitution_text(value) -> str:
    """'r = 1/3' for an exact fraction with a small denominator, 'r = 0.75' otherwise."""
    text = exact_string(value)
    if "/" in text and int(text.split("/")[1]) <= 12:
        numerator, denominator = text.split("/")
        return rf"$r = {numerator}/{denominator}$"
    return rf"$r = {float(value):.6g}$"


def panel_title(axis, text):
    """Give a panel its title, at the top of its axes.

    Placed there rather than by matplotlib's automatic placement, which looks for tick labels
    above the axes (there are none: the ticks point inward, labelled below and left) and
    measures the y axis again at every draw and layout pass.

    Parameters
    ----------
    axis : matplotlib.axes.Axes
        The panel.
    text : str
        The title (mathtext allowed), drawn at 10 points.
    """
    axis.set_title(text, fontsize=10, y=1.0)


def new_figure(rows=1, columns=1, width=6.4, height=4.0, **subplots):
    with matplotlib.rc_context(STYLE):
        figure = Figure(figsize=(width, height), layout="constrained")
        axes = figure.subplots(rows, columns, squeeze=False, **subplots)
    return figure, axes


def _styled(function):
    """Run a figure function with the paper's style in force."""

    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return function(*args, **kwargs)

    wrapper.__doc__, wrapper.__name__ = function.__doc__, function.__name__
    return wrapper


def _laid_out_bounding_box(figure, dpi):
    """Lay the figure out at ``dpi`` (its layout engine, which is then removed) and return
    the box ``savefig(bbox_inches="tight")`` crops to, in inches.

    The layout and the box share one Agg renderer (and its text measurements); without a
    layout engine, ``savefig`` draws the figure once per format, with no draw to find the
    layout or the box first.
    """
    canvas = FigureCanvasAgg(figure)
    shown_dpi = figure.dpi
    figure.set_dpi(dpi)
    try:
        if figure.get_layout_engine() is not None:
            figure.get_layout_engine().execute(figure)
        figure.set_layout_engine(None)
        pad = matplotlib.rcParams["savefig.pad_inches"]
        return figure.get_tightbbox(canvas.get_renderer()).padded(pad)
    finally:
        figure.set_dpi(shown_dpi)


def save_figure(figure, pdf, png, dpi, provenance: dict) -> None:
    """Write the figure as PDF and PNG, atomically and together (temporary names, renamed
    when both are complete: ``io.atomic_paths``).

    The provenance goes into the files' metadata; the PDF carries no creation
    date, so the same tables give the same file.
    """
    description = json.dumps(
        {"package_version": __version__, **provenance}, sort_keys=True, default=str
    )
    pdf_metadata, png_metadata = (
        {
            "Creator": f"bouncing_ball {__version__}",
            "Subject": description,
            "CreationDate": None,
        },
        {"Software": f"bouncing_ball {__version__}", "Description": description},
    )
    with atomic_paths(pdf, png) as (pdf_temporary, png_temporary), matplotlib.rc_context(STYLE):
        # laid out and cropped once, at the PNG's resolution: both formats keep that layout
        # and that box (the PDF's page is the PNG's, to a pixel)
        crop = _laid_out_bounding_box(figure, dpi)
        figure.savefig(png_temporary, metadata=png_metadata, dpi=dpi, bbox_inches=crop)
        figure.savefig(pdf_temporary, metadata=pdf_metadata, bbox_inches=crop)
    logging.info("wrote %s and %s", pdf, png)


def simulated_bins(p0v):
    """The bins of a merged P(0, v) table that can be drawn: not the under/overflow
    bins, at least one collision, a finite error; the martingale-controlled estimate
    (``p0v_martingale``) where the table has one, else the plain counts.  Never the
    return-law controlled ``p0v_controlled``: it leans on eq. (kernel3), the theory the
    figures hold the simulation against."""
    if "p0v_martingale" in p0v and np.isfinite(p0v["p0v_martingale"]).any():
        p0v = p0v.assign(p0v=p0v["p0v_martingale"], p0v_err=p0v["p0v_martingale_err"])
    return drawable_bins(p0v, "v", "p0v")[lambda bins: bins["count"] > 0]


def drawable_bins(table, variable, value):
    """The rows of a merged table on log bins of ``variable`` (columns ``{variable}_lo``,
    ``{variable}_hi``) that can be drawn on log axes: not the under- or overflow bins, a
    positive ``value``, a finite ``{value}_err``."""
    keep = (table[f"{variable}_lo"] > 0) & np.isfinite(table[f"{variable}_hi"])
    keep &= (table[value] > 0) & np.isfinite(table[f"{value}_err"])
    return table[keep]


def _error_bars(axis, x, y, error, log=True, **style):
    """Points with one-sigma error bars; on a log axis the lower bar stops above zero."""
    y, error = np.asarray(y, dtype=float), np.asarray(error, dtype=float)
    lower = np.minimum(error, 0.9 * y) if log else error
    return axis.errorbar(
        x,
        y,
        yerr=[lower, error],
        linestyle="none",
        markersize=3.5,
        markerfacecolor="none",
        elinewidth=0.8,
        **style,
    )


@_styled
def exponents_figure(exponents, critical_restitution):
    """Fig. 1: beta(r), eq. (asym2), and m(r), eqs. (asym3)-(asym6), with r_c and r = 1/2."""
    figure, axes = new_figure(width=5.0, height=3.8)
    axis = axes[0, 0]
    r = exponents.r.to_numpy()
    half = np.isclose(r, 0.5, rtol=0, atol=1e-12)
    axis.plot(r, exponents.beta, color="C0", label=r"$\beta(r)$, eq. (asym2)")
    below, above = r < 0.5, (r > 0.5) & ~half
    axis.plot(
        r[below],
        exponents.m[below],
        color="C3",
        linestyle="--",
        label=r"$m(r)$, eqs. (asym3)-(asym6)",
    )
    # m -> 1 only logarithmically as r -> 1/2 from above (m(0.505) = 0.81): the branch
    # is drawn on to m(1/2) = 1, so that the one jump shown is the one at r = 1/2 from below
    axis.plot(np.r_[0.5, r[above]], np.r_[1.0, exponents.m[above]], color="C3", linestyle="--")
    axis.plot([0.5], [1.0], "o", color="C3", markersize=4)  # m(1/2) = 1
    axis.plot([0.5], [1.5], "o", color="C3", markersize=4, markerfacecolor="white")
    axis.axvline(critical_restitution, color="0.5", linestyle=":", linewidth=0.9)
    axis.annotate(
        r"$r_c$",
        (critical_restitution, 2.45),
        xytext=(4, 0),
        textcoords="offset points",
        va="top",
        color="0.3",
    )
    axis.set_xlim(0.0, 1.0)
    axis.set_ylim(0.0, 2.55)
    axis.set_xlabel(r"$r$")
    axis.set_ylabel(r"$\beta,\ m$")
    axis.legend(loc="upper right")
    return figure


@_styled
def decay_rate_figure(exponents):
    """Fig. 2: q(r), eqs. (asym4) and (asym6); q and dq/dr continuous at r = 1/2."""
    figure, axes = new_figure(width=5.0, height=3.8)
    axis = axes[0, 0]
    axis.plot(exponents.r, exponents.q, color="C0", label=r"$q(r)$, eqs. (asym4), (asym6)")
    axis.axvline(0.5, color="0.5", linestyle=":", linewidth=0.9)
    axis.annotate(
        r"$r = 1/2$",
        (0.5, 0.02),
        xycoords=("data", "axes fraction"),
        xytext=(4, 0),
        textcoords="offset points",
        color="0.3",
    )
    axis.set_yscale("log")
    axis.set_xlim(0.0, 1.0)
    axis.set_xlabel(r"$r$")
    axis.set_ylabel(r"$q$")
    axis.legend(loc="upper right")
    return figure


@_styled
def exact_distribution_figure(panels):
    """Fig. 3: the exact P(x, v) against v, eqs. (fpsol), (psi), (weightfunc2), (constants).

    ``panels``: (r, distribution table with columns x, v, pxv), one panel each.
    """
    figure, axes = new_figure(1, len(panels), width=3.4 * len(panels), height=3.6)
    for axis, (restitution, distribution) in zip(axes[0], panels):
        positions = sorted(distribution.x.unique())
        for index, x in enumerate(positions):
            curve = distribution[distribution.x == x].sort_values("v")
            axis.plot(curve.v, curve.pxv, color=f"C{index}", label=rf"$x = {x:g}$")
        finite = distribution.pxv[np.isfinite(distribution.pxv)]
        # P(0, v) diverges as v -> 0+; the scale is set by the x > 0 curves
        positive = distribution[(distribution.x > 0) & np.isfinite(distribution.pxv)].pxv
        top = (positive.max() if len(positive) else finite.max()) * 1.6
        axis.set_ylim(0.0, top)
        axis.set_xlim(distribution.v.min(), distribution.v.max())
        axis.set_xlabel(r"$v$")
        panel_title(axis, restitution_text(restitution))
        axis.legend(loc="upper right")
    axes[0, 0].set_ylabel(r"$P(x, v)$")
    return figure


def _simulated_points(axis, bins, index):
    return _error_bars(
        axis,
        bins.v,
        bins.p0v,
        bins.p0v_err,
        color="k",
        marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
        label="simulation",
        zorder=3,
    )


def _finish_outgoing_speed_panel(axis, bins, restitution):
    """Log-log axes of a P(0, v) panel (Figs. 4, 5), scaled to the simulated points."""
    axis.set_xscale("log")
    axis.set_yscale("log")
    positive = bins.p0v[bins.p0v > 0]
    axis.set_ylim(positive.min() / 5, positive.max() * 5)
    axis.set_xlabel(r"$v$")
    panel_title(axis, restitution_text(restitution))
    axis.legend(loc="lower left")


def _fitted(fits, window, parameter):
    row = fits[
        (fits.source == "simulation")
        & (fits.window == window)
        & (fits.fit == "fixed_exponents")
        & (fits.parameter == parameter)
    ]
    return float(row.value.iloc[0]), float(row.v_min.iloc[0]), float(row.v_max.iloc[0])


@_styled
def asymptotic_forms_figure(panels):
    """Fig. 4: simulated P(0, v) with the small-v form A v^-beta, eqs. (asym1), (asym2)
    (dashed), the large-v form A v^-m exp(-q v), eqs. (asym3)-(asym6) (solid), prefactors
    fitted to the simulation, and the solver's P(0, v), eq. (inteq) (dotted).

    ``panels``: dicts with ``restitution``, ``simulated`` (merged p0v table),
    ``solver`` (v, p0v) and ``fits`` (the fit table of that r).
    """
    figure, axes = new_figure(1, len(panels), width=3.6 * len(panels), height=3.8)
    for index, (axis, panel) in enumerate(zip(axes[0], panels)):
        bins = simulated_bins(panel["simulated"])
        _simulated_points(axis, bins, index)
        low, high = bins.v_lo.min(), bins.v_hi.max()
        solver = panel["solver"][(panel["solver"].v >= low) & (panel["solver"].v <= high)]
        axis.plot(
            solver.v, solver.p0v, color="0.4", linestyle=":", zorder=5, label="solver, eq. (inteq)"
        )
        fits = panel["fits"]
        prefactor, v_min, v_max = _fitted(fits, "small_speed", "prefactor")
        beta, _, _ = _fitted(fits, "small_speed", "beta")
        if np.isfinite(prefactor):
            v = np.geomspace(low, high, 300)
            axis.plot(
                v,
                prefactor * v**-beta,
                color="C0",
                linestyle="--",
                zorder=4,
                label=rf"$A v^{{-\beta}}$, $\beta = {beta:.4g}$",
            )
            inside = (v >= v_min) & (v <= v_max)
            axis.plot(
                v[inside], prefactor * v[inside] ** -beta, color="C0", linewidth=3, alpha=0.35
            )
        prefactor, v_min, v_max = _fitted(fits, "large_speed", "prefactor")
        m, _, _ = _fitted(fits, "large_speed", "m")
        q, _, _ = _fitted(fits, "large_speed", "q")
        if np.isfinite(prefactor):
            v = np.geomspace(low, high, 300)
            form = prefactor * v**-m * np.exp(-q * v)
            axis.plot(
                v,
                form,
                color="C3",
                zorder=4,
                label=rf"$A v^{{-m}} e^{{-qv}}$, $m = {m:.4g}$, $q = {q:.4g}$",
            )
            inside = (v >= v_min) & (v <= v_max)
            axis.plot(v[inside], form[inside], color="C3", linewidth=3, alpha=0.35)
        _finish_outgoing_speed_panel(axis, bins, panel["restitution"])
    axes[0, 0].set_ylabel(r"$P(0, v)$")
    return figure


@_styled
def exact_comparison_figure(panels):
    """Fig. 5: simulated P(0, v) against eq. (P(0,v)) with eq. (constants), no free parameter.

    ``panels``: dicts with ``restitution``, ``simulated`` (merged p0v table),
    ``exact`` (v, p0v).
    """
    figure, axes = new_figure(1, len(panels), width=3.6 * len(panels), height=3.8)
    for index, (axis, panel) in enumerate(zip(axes[0], panels)):
        bins = simulated_bins(panel["simulated"])
        low, high = bins.v_lo.min(), bins.v_hi.max()
        exact = panel["exact"][(panel["exact"].v >= low) & (panel["exact"].v <= high)]
        axis.plot(exact.v, exact.p0v, color="C0", label="exact, eqs. (P(0,v)), (constants)")
        _simulated_points(axis, bins, index)
        _finish_outgoing_speed_panel(axis, bins, panel["restitution"])
    axes[0, 0].set_ylabel(r"$P(0, v)$")
    return figure


TIME_AVERAGE_LABELS = {
    "mean_x": r"$\langle x\rangle$",
    "delta_x": r"$\Delta x$",
    "collision_rate": r"$I$",
}


@_styled
def time_averages_figure(solved, simulated, exact, critical_restitution, per_restitution=None):
    """Fig. 6: <x>, Delta x and I against 1 - r on a log axis, so that the elastic end opens
    up: the solver's curve over the grid (eq. (inteq) with the Ito identities; I by
    eq. (collrate)), the solver at each simulated r, the quasi-elastic forms to first order in
    1 - r (``quasi_elastic.quasi_elastic_form``) where 1 - r <= 0.1, the simulation's points,
    the exact values at r = 1/2 and 1/3.

    ``solved``: table r, mean_x, delta_x, collision_rate; ``simulated``: merged
    summary rows (with ``*_err``); ``exact``: exact summary rows; ``per_restitution``: the
    solver's summary rows of the simulated r (optional).
    """
    from ..quasi_elastic import quasi_elastic_form

    figure, axes = new_figure(3, 1, width=4.6, height=7.2, sharex=True)
    shown_r = [solved.r, simulated.r if len(simulated) else []]
    if per_restitution is not None and len(per_restitution):
        shown_r.append(per_restitution.r)
    largest = max(
        float(np.max(np.asarray(values, dtype=float))) for values in shown_r if len(values)
    )
    inelasticity = np.geomspace(min(0.1, 0.5 * (1.0 - largest)), 0.1, 60)
    for axis, quantity in zip(axes[:, 0], ("mean_x", "delta_x", "collision_rate")):
        values = solved[quantity].to_numpy()
        finite = np.isfinite(values)
        axis.plot(1.0 - solved.r[finite], values[finite], color="C0", label="solver, eq. (inteq)")
        if per_restitution is not None and len(per_restitution):
            axis.plot(
                1.0 - per_restitution.r,
                per_restitution[quantity],
                "s",
                color="C0",
                markersize=5,
                markerfacecolor="none",
                label="solver at each simulated r",
            )
        limit = [quasi_elastic_form(quantity, 1.0 - e) for e in inelasticity]
        axis.plot(
            inelasticity,
            limit,
            color="C2",
            linestyle="--",
            linewidth=1.0,
            label="quasi-elastic form, to first order in 1 - r",
        )
        if len(simulated):
            _error_bars(
                axis,
                1.0 - simulated.r,
                simulated[quantity],
                simulated[f"{quantity}_err"],
                color="k",
                marker="o",
                label="simulation",
                zorder=3,
            )
        if len(exact):
            axis.plot(
                1.0 - exact.r,
                exact[quantity],
                "x",
                color="C3",
                markersize=6,
                label="exact, r = 1/2, 1/3",
            )
        axis.set_ylabel(TIME_AVERAGE_LABELS[quantity])
        axis.set_yscale("log")  # <x> and Delta x grow without bound as r -> 1, I as r -> r_c
        if quantity == "collision_rate":
            axis.axvline(1.0 - critical_restitution, color="0.5", linestyle=":", linewidth=0.9)
            axis.annotate(
                r"$r_c$: $I = \infty$ below",
                (1.0 - critical_restitution, 0.9),
                xycoords=("data", "axes fraction"),
                xytext=(4, 0),
                textcoords="offset points",
                ha="left",
                color="0.3",
            )
    axes[0, 0].legend(loc="upper left", fontsize=7)
    bottom = axes[-1, 0]
    bottom.set_xscale("log")
    bottom.set_xlim(1.0, 0.5 * inelasticity[0])  # r grows to the right, as in the paper
    bottom.set_xlabel(r"$1 - r$")
    top = axes[0, 0].secondary_xaxis("top", functions=(lambda e: e, lambda e: e))
    ticks = [r for r in (0.1, 0.5, 0.9, 0.99, 0.999, 0.9999) if 1.0 - r >= 0.5 * inelasticity[0]]
    top.set_xticks([1.0 - r for r in ticks], [f"{r:g}" for r in ticks])
    top.xaxis.set_minor_locator(NullLocator())
    top.set_xlabel(r"$r$")
    return figure


@_styled
def residuals_figure(panels):
    """Fig. 7: (simulation - solver) / sigma of every P(0, v) bin, one row per simulated r,
    against q(r) v: the speed in units of the large-v decay length 1/q of eqs. (asym4)-(asym6),
    so that every r's bins, which follow its own scales, read alike (each panel spans its own
    bins).

    ``panels``: (r, residual table with columns v, residual) pairs.
    """
    from ..asymptotics import large_speed_decay_rate

    # each r on its own range of speeds: near r_c the bins reach down by decades
    figure, axes = new_figure(len(panels), 1, width=5.0, height=1.3 + 1.3 * len(panels))
    for index, (axis, (restitution, residuals)) in enumerate(zip(axes[:, 0], panels)):
        axis.axhspan(-2, 2, color="0.92", zorder=0)
        axis.axhline(0.0, color="0.5", linewidth=0.8)
        q = large_speed_decay_rate(float(restitution))
        axis.plot(
            q * residuals.v,
            residuals.residual,
            linestyle="none",
            color="k",
            marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
            markersize=3.5,
            markerfacecolor="none",
        )
        chi2 = float(np.mean(residuals.residual**2)) if len(residuals) else np.nan
        axis.text(
            0.01,
            0.93,
            f"{restitution_text(restitution)}:  "
            rf"$\chi^2/n = {chi2:.2f}$, $n = {len(residuals)}$"
            + (
                f", v in [{residuals.v.min():.2g}, {residuals.v.max():.2g}]"
                if len(residuals)
                else ", no bin with counts"
            ),
            transform=axis.transAxes,
            va="top",
            bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.85, "pad": 1.5},
            zorder=5,
        )
        limit = max(4.5, 1.3 * float(np.max(np.abs(residuals.residual)))) if len(residuals) else 4.0
        axis.set_ylim(-limit, limit)
        axis.set_xscale("log")
        axis.set_ylabel(r"$\Delta P / \sigma$")
    axes[-1, 0].set_xlabel(r"$q(r)\, v$")
    return figure


def _panel_grid(count, width=3.4, height=3.2):
    """Axes for ``count`` panels, two to a row."""
    columns = min(count, 2)
    rows = -(-count // columns)
    figure, axes = new_figure(rows, columns, width=width * columns, height=height * rows)
    for axis in axes.ravel()[count:]:
        axis.set_visible(False)
    return figure, axes.ravel()[:count]


@_styled
def joint_distribution_figure(panels):
    """Fig. 8 (past the paper, the paper's Fig. 3 for any r): P(x, v) against v at several x
    from the solver, eqs. (fpsol), (weightfunc), (P(x)1); the simulation's time-weighted
    cells of the x bin holding each x (points, one-sigma errors); the exact curve where r is
    1/2 or 1/3 (eq. (weightfunc2)); over the velocities where some curve is above 1e-3 of the
    tallest.

    ``panels``: dicts with ``restitution``, ``solver`` (x, v, pxv), ``simulated``
    (x_lo, x_hi, v_lo, v_hi, pxv, pxv_err) and ``exact`` (x, v, pxv, or None).
    """
    figure, axes = _panel_grid(len(panels))
    for axis, panel in zip(axes, panels):
        solver, simulated = panel["solver"], panel["simulated"]
        positions = [x for x in sorted(solver.x.unique()) if x > 0]
        top = 0.0
        for index, x in enumerate(positions):
            color = f"C{index}"
            curve = solver[solver.x == x].sort_values("v")
            axis.plot(curve.v, curve.pxv, color=color, label=rf"$x = {x:g}$")
            top = max(top, float(np.nanmax(curve.pxv)))
            if panel.get("exact") is not None:
                exact = panel["exact"][np.isclose(panel["exact"].x, x, rtol=1e-12, atol=0)]
                axis.plot(exact.v, exact.pxv, color="k", linestyle=":", linewidth=0.9)
            cells = simulated[(simulated.x_lo <= x) & (simulated.x_hi > x)]
            cells = cells[
                np.isfinite(cells.v_lo)
                & np.isfinite(cells.v_hi)
                & (cells.v_lo >= curve.v.min())
                & (cells.v_hi <= curve.v.max())
                & np.isfinite(cells.pxv_err)
            ]
            if len(cells):
                _error_bars(
                    axis,
                    0.5 * (cells.v_lo + cells.v_hi),
                    cells.pxv,
                    cells.pxv_err,
                    log=False,
                    color=color,
                    marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
                    zorder=3,
                )
        if panel.get("exact") is not None:
            axis.plot([], [], color="k", linestyle=":", linewidth=0.9, label="exact")
        axis.set_ylim(0.0, 1.15 * top if top > 0 else None)
        # the velocities where some curve is above 1e-3 of the tallest: the body of P(x, v)
        # on a linear axis (the table spans the scales of r, its tails far below)
        body = solver[(solver.x > 0) & (solver.pxv >= 1e-3 * top)].v
        shown = (
            (body.min(), body.max()) if len(body) and top > 0 else (solver.v.min(), solver.v.max())
        )
        axis.set_xlim(*shown)
        axis.set_xlabel(r"$v$")
        axis.set_ylabel(r"$P(x, v)$")
        panel_title(axis, restitution_text(panel["restitution"]))
        axis.legend(loc="upper right")
    return figure


@_styled
def position_density_figure(panels):
    """Fig. 9 (past the paper): P(x) for every simulated r: the solver through w(F),
    eqs. (weightfunc), (P(x)1) (line), the simulation's bins (points, one-sigma errors) and
    the exact eq. (P(x)2) where r is 1/2 or 1/3 (dotted).  Each panel spans the heights
    that hold all but about 1e-6 of the time (where x P(x) is above 1e-6 of its largest
    value), and says how much of the time the simulated bins leave outside, or that they
    recorded none.

    ``panels``: dicts with ``restitution``, ``solver`` (x, px), ``simulated`` (x_lo, x_hi,
    x, px, px_err), ``exact`` (x, px, or None) and ``outside`` (the simulation's
    ``outside`` provenance, optional).
    """
    figure, axes = _panel_grid(len(panels))
    for index, (axis, panel) in enumerate(zip(axes, panels)):
        simulated = panel["simulated"]
        bins = drawable_bins(simulated, "x", "px")
        _error_bars(
            axis,
            bins.x,
            bins.px,
            bins.px_err,
            color="k",
            marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
            label="simulation",
            zorder=3,
        )
        solver = panel["solver"]
        axis.plot(solver.x, solver.px, color="C0", label="solver, eq. (P(x)1)")
        if panel.get("exact") is not None:
            axis.plot(
                panel["exact"].x,
                panel["exact"].px,
                color="C3",
                linestyle=":",
                label="exact, eq. (P(x)2)",
            )
        axis.set_xscale("log")
        axis.set_yscale("log")
        mass = (solver.x * solver.px).to_numpy()
        body = solver[np.isfinite(mass) & (mass >= 1e-6 * np.nanmax(mass))]
        if len(body):
            axis.set_xlim(body.x.min(), body.x.max())
            axis.set_ylim(body.px.min() / 3, body.px.max() * 5)
        outside = (panel.get("outside") or {}).get("position")
        note = (
            "no simulated time in the bins"
            if not len(bins)
            else f"simulated bins: {outside['outside']:.0e} of the time outside"
            if outside
            else ""
        )
        if note:
            axis.text(
                0.98,
                0.97,
                note,
                transform=axis.transAxes,
                ha="right",
                va="top",
                fontsize=7,
                color="0.3",
            )
        axis.set_xlabel(r"$x$")
        axis.set_ylabel(r"$P(x)$")
        panel_title(axis, restitution_text(panel["restitution"]))
        axis.legend(loc="lower left")
    return figure


@_styled
def flight_time_figure(panels):
    """Fig. 10 (past the paper): the distribution of the time between bounces, rho(T), from
    McKean's first-passage law with gravity, eqs. (0g), (GgP), and the solver's P(0, u)
    (line); the simulation's flights (points); the short- and long-time forms (dashed,
    dotted).  Below r_c, where rho is not defined, nu(T) = I rho(T) (flights per unit time).

    ``panels``: dicts with ``restitution``, ``solver`` (t, density, rate_density,
    short_time_form, long_time_form), ``collision_rate``, ``long_time_decay_rate`` (kappa of
    nu ~ e^(-kappa T)) and ``simulated`` (t_lo, t_hi, t, density, density_err).
    """
    figure, axes = _panel_grid(len(panels))
    for index, (axis, panel) in enumerate(zip(axes, panels)):
        solver, rate = panel["solver"], panel["collision_rate"]
        per_flight = bool(np.isfinite(rate))
        scale = 1.0 / rate if per_flight else 1.0
        curve = solver.density if per_flight else solver.rate_density
        axis.plot(solver.t, curve, color="C0", label="McKean + solver")
        # each form where it applies: short T below the decay time 1/kappa, long T beyond a
        # fifth of it
        decay_time = 1.0 / panel["long_time_decay_rate"]
        short, long = solver[solver.t <= decay_time], solver[solver.t >= 0.2 * decay_time]
        axis.plot(
            short.t,
            short.short_time_form * scale,
            color="C2",
            linestyle="--",
            label=r"short $T$",
        )
        axis.plot(
            long.t,
            long.long_time_form * scale,
            color="C3",
            linestyle=":",
            label=r"long $T$",
        )
        simulated = panel["simulated"]
        bins = drawable_bins(simulated, "t", "density")
        if per_flight and len(bins):
            _error_bars(
                axis,
                bins.t,
                bins.density,
                bins.density_err,
                color="k",
                marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
                label="simulation",
                zorder=3,
            )
        axis.set_xscale("log")
        axis.set_yscale("log")
        # scaled to the simulated points where there are some, else to 20 decades of the curve
        shown = bins.density if per_flight and len(bins) else curve[np.isfinite(curve)]
        shown = shown[shown > 0]
        if len(shown):
            axis.set_ylim(max(shown.min() / 10, shown.max() * 1e-20), shown.max() * 5)
        axis.set_xlabel(r"$T$")
        axis.set_ylabel(r"$\rho(T)$" if per_flight else r"$\nu(T)$")
        panel_title(axis, restitution_text(panel["restitution"]))
        axis.legend(loc="lower left")
    return figure


@_styled
def return_speed_figure(panels, outgoing_speeds):
    """Fig. 11 (past the paper): the return-speed law, eq. (kernel3): the probability
    density of the speed v at the next bounce for a ball that leaves with speed u in a bin,
    v G_g(v, u) averaged over the bin with weight u P(0, u) (line), against the simulated
    (outgoing, return) pairs (points, one-sigma errors), one panel per outgoing-speed bin
    holding a speed of ``outgoing_speeds``.

    ``panels``: dicts with ``restitution``, ``solver`` and ``simulated`` (u_lo, u_hi, v_lo,
    v_hi, probability[, probability_err]).
    """
    figure, axes = _panel_grid(len(outgoing_speeds))
    for axis, speed in zip(axes, outgoing_speeds):
        drawn = []
        for index, panel in enumerate(panels):
            theory, simulated = panel["solver"], panel["simulated"]
            row = theory[(theory.u_lo <= speed) & (theory.u_hi > speed)]
            row = row[(row.v_lo > 0) & np.isfinite(row.v_hi)]
            width = row.v_hi - row.v_lo
            centre = np.sqrt(row.v_lo * row.v_hi)
            label = restitution_text(panel["restitution"])
            axis.plot(centre, row.probability / width, color=f"C{index}", label=label)
            drawn.append((centre.to_numpy(), (row.probability / width).to_numpy()))
            cells = simulated[(simulated.u_lo <= speed) & (simulated.u_hi > speed)]
            cells = drawable_bins(cells, "v", "probability")
            width = cells.v_hi - cells.v_lo
            _error_bars(
                axis,
                np.sqrt(cells.v_lo * cells.v_hi),
                cells.probability / width,
                cells.probability_err / width,
                color=f"C{index}",
                marker=SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)],
                zorder=3,
            )
            if len(row):
                u_lo, u_hi = float(row.u_lo.iloc[0]), float(row.u_hi.iloc[0])
                panel_title(axis, rf"${u_lo:.3g} \leq u < {u_hi:.3g}$")
        axis.set_xscale("log")
        axis.set_yscale("log")
        # four decades below the peak: where the law and the data can be told apart
        centres = np.concatenate([c for c, _ in drawn]) if drawn else np.array([])
        densities = np.concatenate([d for _, d in drawn]) if drawn else np.array([])
        if densities.size and np.nanmax(densities) > 0:
            top = float(np.nanmax(densities))
            shown = centres[densities > 1e-4 * top]
            axis.set_ylim(1e-4 * top, 3.0 * top)
            axis.set_xlim(shown.min() / 1.5, shown.max() * 1.5)
        axis.set_xlabel(r"return speed $v$")
        axis.set_ylabel(r"$v\, G_g(v, u)$")
        axis.legend(loc="lower left")
    return figure


@_styled
def relaxation_figure(theory, panels):
    """Fig. 12 (past the paper): the relaxation of the bounce chain.  Left: the correlation
    length n_c = -1 / ln lambda_2 in bounces against 1 - r, from the solver's matrix of
    eq. (inteq) (line; ``theory``: r, correlation_bounces, simulated), with the quasi-elastic
    asymptote -1 / ln r, and the simulated decay rates (points, one-sigma errors).  Right:
    the simulated principal correlation mu_k of (ln u_n, u_n) over lags k (filled) and the
    autocorrelation rho_k of ln u_n (open) at each simulated r, against lambda_2^k (lines).
    Third: the slowest time of the process 1 / gamma (``theory``: relaxation_time, from the
    tilted bounce operator) and the bounce chain's n_c <T> (bounce_chain_time) against 1 - r,
    with their asymptotes (64/9) (1 - r)^-2 and (8/3) (1 - r)^-2.

    ``panels``: dicts with ``restitution``, ``eigenvalue`` (the theory's lambda_2) and
    ``simulated`` (the merged bounce_chain table: lag, autocorrelation,
    principal_correlation with their _err, correlation_bounces from decay_rate).
    """
    figure, axes = new_figure(1, 3, width=13.0, height=3.8)
    left, right, times = axes[0, 0], axes[0, 1], axes[0, 2]
    curve = theory[~theory.simulated].sort_values("r")
    eps = 1.0 - curve.r.to_numpy()
    timed = np.isfinite(
        curve.relaxation_time.to_numpy(dtype=float)
    )  # figures.fig12_time_inelasticity
    times.plot(
        eps[timed],
        curve.relaxation_time[timed],
        color="k",
        marker=".",
        label=r"$1/\gamma$, tilted operator",
    )
    times.plot(
        eps, curve.bounce_chain_time, color="C3", label=r"$n_c \langle T\rangle$, bounce chain"
    )
    times.plot(
        eps,
        (64.0 / 9.0) / eps**2,
        color="0.5",
        linestyle="--",
        label=r"$(64/9)(1-r)^{-2}$",
    )
    times.plot(
        eps, (8.0 / 3.0) / eps**2, color="C3", alpha=0.5, linestyle=":", label=r"$(8/3)(1-r)^{-2}$"
    )
    times.set_xscale("log")
    times.set_yscale("log")
    times.set_xlabel(r"$1 - r$")
    times.set_ylabel(r"time ($\Lambda/g^2$)")
    times.legend(loc="upper right")
    left.plot(eps, curve.correlation_bounces, color="k", label=r"$-1/\ln\lambda_2$, solver")
    left.plot(eps, -1.0 / np.log(curve.r), color="0.5", linestyle="--", label=r"$-1/\ln r$")
    for index, panel in enumerate(panels):
        table = panel["simulated"]
        rate = float(table.decay_rate.iloc[0])
        rate_err = float(table.decay_rate_err.iloc[0])
        if not np.isfinite(rate):
            continue
        marker = SIMULATION_MARKERS[index % len(SIMULATION_MARKERS)]
        style = {"color": f"C{index}", "marker": marker}
        _error_bars(
            left,
            [1.0 - float(panel["restitution"])],
            [1.0 / rate],
            [rate_err / rate**2],
            label=restitution_text(panel["restitution"]),
            zorder=3,
            **style,
        )
        lags = table.lag.to_numpy()
        shown = table.principal_correlation > 0
        _error_bars(
            right,
            lags[shown],
            table.principal_correlation[shown],
            table.principal_correlation_err[shown],
            label=restitution_text(panel["restitution"]),
            zorder=3,
            **style,
        )
        positive = table.autocorrelation > 0
        right.plot(
            lags[positive],
            table.autocorrelation[positive],
            linestyle="none",
            marker=marker,
            markersize=3.0,
            markerfacecolor="white",
            markeredgecolor=f"C{index}",
            alpha=0.6,
        )
        k = np.linspace(0.0, lags.max(), 50)
        right.plot(k, panel["eigenvalue"] ** k, color=f"C{index}", linewidth=0.9)
    left.set_xscale("log")
    left.set_yscale("log")
    left.set_xlabel(r"$1 - r$")
    left.set_ylabel(r"$n_c$ (bounces)")
    left.legend(loc="upper right")
    right.set_yscale("log")
    right.set_ylim(1e-2, 1.2)
    right.set_xlabel(r"lag $k$ (bounces)")
    right.set_ylabel(r"$\mu_k$ (filled), $\rho_k$ of $\ln u$ (open)")
    right.legend(loc="lower left")
    return figure


def quasi_elastic_figure(curves):
    """Fig. 13 (past the paper): the collapse of P(0, v) as r -> 1.  Left: the solver's
    (1 - r)^-3 P(0, w / (1 - r)) against w = (1 - r) v at each r of ``curves`` (the table of
    ``quasi_elastic.scaled_speed_curves``: r, w, scaled_p0v, limit, c1_measured, c1_predicted),
    with the limit (27/32) e^(-3w/2).  Right: (scaled / limit - 1) / (1 - r) against the
    predicted first correction p1(w) = 5/2 - 3w/2.
    """
    figure, axes = new_figure(1, 2, width=9.0, height=3.8)
    left, right = axes[0, 0], axes[0, 1]
    for index, (r, curve) in enumerate(curves.groupby("r", sort=True)):
        style = {"color": f"C{index}", "linewidth": 1.2}
        label = f"$r = {r:g}$"
        left.plot(curve.w, curve.scaled_p0v, label=label, **style)
        right.plot(curve.w, curve.c1_measured, label=label, **style)
    limit = curves.drop_duplicates("w").sort_values("w")
    left.plot(limit.w, limit.limit, color="k", linestyle="--", linewidth=1.0, label="limit")
    right.plot(
        limit.w, limit.c1_predicted, color="k", linestyle="--", linewidth=1.0, label=r"$p_1(w)$"
    )
    left.set_xscale("log")
    left.set_yscale("log")
    left.set_xlabel(r"$w = (1 - r)\,v$")
    left.set_ylabel(r"$(1 - r)^{-3} P(0, w/(1 - r))$")
    left.legend(loc="lower left")
    right.set_xscale("log")
    right.set_xlabel(r"$w = (1 - r)\,v$")
    right.set_ylabel(r"(scaled / limit $- 1$) / $(1 - r)$")
    right.legend(loc="lower left")
    return figure
