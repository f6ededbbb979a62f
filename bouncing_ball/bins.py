"""Log- and evenly spaced bins, each with an underflow and an overflow bin.

A ``LogBins(lo, hi, per_decade)`` has the finite edges e_0 = lo < ... < e_n = hi
and n + 2 bins: index 0 holds everything below lo (including 0 and negative
values), index j + 1 holds [e_j, e_{j+1}), and index n + 1 holds [hi, inf).
A ``LinearBins(lo, hi, width)`` is the same with evenly spaced edges
e_j = lo + j width; its underflow bin is (-inf, lo).
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LogBins:
    lo: float
    hi: float
    per_decade: int

    def __post_init__(self):
        if not (0.0 < self.lo < self.hi):
            raise ValueError(f"bins need 0 < lo < hi, got lo={self.lo}, hi={self.hi}")
        if self.per_decade < 1:
            raise ValueError(f"bins need per_decade >= 1, got {self.per_decade}")

    @property
    def n(self) -> int:
        """Number of finite bins (hi is rounded up to a whole bin)."""
        return int(np.ceil(np.log10(self.hi / self.lo) * self.per_decade - 1e-9))

    @property
    def edges(self) -> np.ndarray:
        """The n + 1 finite edges."""
        return self.lo * 10.0 ** (np.arange(self.n + 1) / self.per_decade)

    @property
    def lower(self) -> np.ndarray:
        """Lower edge of each of the n + 2 bins (0 for the underflow bin)."""
        return np.concatenate([[0.0], self.edges])

    @property
    def upper(self) -> np.ndarray:
        """Upper edge of each of the n + 2 bins (inf for the overflow bin)."""
        return np.concatenate([self.edges, [np.inf]])


@dataclass(frozen=True)
class LinearBins:
    lo: float
    hi: float
    width: float

    def __post_init__(self):
        if not self.lo < self.hi:
            raise ValueError(f"bins need lo < hi, got lo={self.lo}, hi={self.hi}")
        if not self.width > 0.0:
            raise ValueError(f"bins need width > 0, got width={self.width}")

    @property
    def n(self) -> int:
        """Number of finite bins (hi is rounded up to a whole bin)."""
        return int(np.ceil((self.hi - self.lo) / self.width - 1e-9))

    @property
    def edges(self) -> np.ndarray:
        """The n + 1 finite edges."""
        return self.lo + self.width * np.arange(self.n + 1)

    @property
    def lower(self) -> np.ndarray:
        """Lower edge of each of the n + 2 bins (-inf for the underflow bin)."""
        return np.concatenate([[-np.inf], self.edges])

    @property
    def upper(self) -> np.ndarray:
        """Upper edge of each of the n + 2 bins (inf for the overflow bin)."""
        return np.concatenate([self.edges, [np.inf]])


# the config's specifications of bins and grids, e.g. {lo, hi, per_decade} and {min, max, points}
def log_bins(spec: dict) -> LogBins:
    return LogBins(float(spec["lo"]), float(spec["hi"]), int(spec["per_decade"]))


def linear_bins(spec: dict) -> LinearBins:
    return LinearBins(float(spec["lo"]), float(spec["hi"]), float(spec["width"]))


def log_grid(spec: dict):
    return np.geomspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


def linear_grid(spec: dict):
    return np.linspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(8)


def outgoing_speed_bin_average(density, lower, upper):
    """int_lo^hi v P(0, v) dv / int_lo^hi v dv for each bin [lo, hi): what a bin of
    outgoing speeds measures (eq. (collrate): collisions with v_out in the bin come at the
    rate int v P(0, v) dv).  ``density`` is P(0, v) as a function of an array of v;
    8-point Gauss-Legendre in ln v on each bin."""
    lower = np.asarray(lower, dtype=float)[:, None]
    upper = np.asarray(upper, dtype=float)[:, None]
    half = 0.5 * np.log(upper / lower)
    v = np.exp(half * _GAUSS_NODES[None, :] + 0.5 * np.log(upper * lower))
    flux = half[:, 0] * ((v * v * density(v)) @ _GAUSS_WEIGHTS)
    return flux / (0.5 * (upper[:, 0] ** 2 - lower[:, 0] ** 2))
