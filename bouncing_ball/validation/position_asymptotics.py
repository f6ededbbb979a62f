"""The asymptotics of P(x) for any r: results/tables/position_asymptotics."""

import pandas as pd

__all__ = [
    "position_asymptotics_table",
    "position_asymptotics_markdown",
    "POSITION_EXPONENTS",
]

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them


# ---- the asymptotics of P(x) for any r (results/tables/position_asymptotics) ----

POSITION_EXPONENTS = {
    "small_x_power": "P(x) - P(0) or P(x) ~ x^a, x -> 0: a = (1 - beta)/3",
    "small_x_power_at_zero_speed": "P(x, 0) ~ x^a, x -> 0: a = -beta/3",
    "large_x_rate": "P(x) ~ x^c exp(-b x^(1/2)), x -> inf: b",
    "large_x_power": "P(x) ~ x^c exp(-b x^(1/2)), x -> inf: c",
}


def position_asymptotics_table(summaries) -> pd.DataFrame:
    """The exponents of P(x) at small and large x, measured and predicted, for each r.

    Parameters
    ----------
    summaries : iterable of (str, mapping)
        The r label and the solver's summary row (with ``<exponent>_measured``, from the
        solver's P(x) of eq. (P(x)1), and ``<exponent>_predicted``, docs/distribution.md).

    Returns
    -------
    pandas.DataFrame
        One row per r and exponent of ``POSITION_EXPONENTS``: r_label, r, exponent, meaning,
        measured, predicted, difference.
    """
    rows = []
    for label, summary in summaries:
        for exponent, meaning in POSITION_EXPONENTS.items():
            measured = float(summary[f"{exponent}_measured"])
            predicted = float(summary[f"{exponent}_predicted"])
            rows.append(
                {
                    "r_label": label,
                    "r": float(summary["r"]),
                    "exponent": exponent,
                    "meaning": meaning,
                    "measured": measured,
                    "predicted": predicted,
                    "difference": measured - predicted,
                }
            )
    return pd.DataFrame(rows)


def position_asymptotics_markdown(table: pd.DataFrame) -> str:
    """The exponents of P(x) for a reader, as results/tables/position_asymptotics.md.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of ``position_asymptotics_table``.

    Returns
    -------
    str
        A Markdown table and a note on how the exponents are measured.
    """
    shown = pd.DataFrame(
        {
            "r": table.r_label,
            "exponent": table.meaning,
            "measured (solver's P(x))": table.measured.map(lambda value: f"{value:.6f}"),
            "predicted": table.predicted.map(lambda value: f"{value:.6f}"),
            "difference": table.difference.map(lambda value: f"{value:+.1e}"),
        }
    )
    note = (
        "\nSmall x: local slopes at x ~ 1e-7, with corrections of relative order "
        "x^((beta - 1)/3) for 1 < beta < 2 and x^(1/3) otherwise (so the differences shrink "
        "slowly as x -> 0: x^(1/6) = 0.07 at x = 1e-7 and r = 1/3); at r = 1/2 (beta = 1) P(x) ~ -ln x, whose "
        "local slope goes to 0 only like 1/ln x. Large x: a fit of ln P(x) over the window where "
        "w(F) is computed (docs/distribution.md).\n"
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n" + note
