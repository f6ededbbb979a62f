"""Log- and evenly spaced bins, each with an underflow and an overflow bin.

A ``LogBins(lo, hi, per_decade)`` has the finite edges e_0 = lo < ... < e_n = hi
and n + 2 bins: index 0 holds everything below lo (including 0 and negative
values), index j + 1 holds [e_j, e_{j+1}), and index n + 1 holds [hi, inf).
A ``LinearBins(lo, hi, width)`` is the same with evenly spaced edges
e_j = lo + j width; its underflow bin is (-inf, lo).
"""

from dataclasses import dataclass

import numpy as np

__all__ = [
    "LogBins",
    "LinearBins",
    "log_bins",
    "linear_bins",
    "log_grid",
    "linear_grid",
    "outgoing_speed_bin_average",
]


@dataclass(frozen=True)
class LogBins:
    """Logarithmically spaced bins on [lo, hi), with an underflow and an overflow bin.

    The bins of the tallies of outgoing speeds, heights and flight times.

    Parameters
    ----------
    lo, hi : float
        The lowest and highest finite edge, 0 < lo < hi (hi is rounded up to a whole bin).
    per_decade : int
        Bins per factor 10, at least 1.

    Attributes
    ----------
    n : int
        The number of finite bins.
    edges : numpy.ndarray
        The n + 1 finite edges, lo 10^(j / per_decade).
    lower, upper : numpy.ndarray
        The lower and upper edge of each of the n + 2 bins: index 0 is the underflow bin
        [0, lo) (it also holds 0 and negative values), index n + 1 the overflow bin [hi, inf).

    Raises
    ------
    ValueError
        If not 0 < lo < hi, or per_decade < 1.

    Examples
    --------
    >>> from bouncing_ball.bins import LogBins
    >>> bins = LogBins(0.01, 1.0, 1)
    >>> print(bins.n, bins.edges, bins.lower, bins.upper)
    2 [0.01 0.1  1.  ] [0.   0.01 0.1  1.  ] [0.01 0.1  1.    inf]
    """

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
    """Evenly spaced bins on [lo, hi), with an underflow and an overflow bin.

    The velocity bins of the tallied P(x, v).

    Parameters
    ----------
    lo, hi : float
        The lowest and highest finite edge, lo < hi (hi is rounded up to a whole bin).
    width : float
        The width of a bin, > 0.

    Attributes
    ----------
    n : int
        The number of finite bins.
    edges : numpy.ndarray
        The n + 1 finite edges, lo + j width.
    lower, upper : numpy.ndarray
        The lower and upper edge of each of the n + 2 bins: index 0 is the underflow bin
        (-inf, lo), index n + 1 the overflow bin [hi, inf).

    Raises
    ------
    ValueError
        If not lo < hi, or not width > 0.

    Examples
    --------
    >>> from bouncing_ball.bins import LinearBins
    >>> bins = LinearBins(-1.0, 1.0, 0.5)
    >>> print(bins.n, bins.edges, bins.lower[:2], bins.upper[-2:])
    4 [-1.  -0.5  0.   0.5  1. ] [-inf -1.] [ 1. inf]
    """

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


def log_bins(spec: dict) -> LogBins:
    """``LogBins`` from the config's specification of a bin set.

    Parameters
    ----------
    spec : dict
        The keys lo, hi and per_decade (as in the config's ``simulation`` section).

    Returns
    -------
    LogBins

    Examples
    --------
    >>> from bouncing_ball.bins import log_bins
    >>> log_bins({"lo": 1e-3, "hi": 1e3, "per_decade": 5}).n
    30
    """
    return LogBins(float(spec["lo"]), float(spec["hi"]), int(spec["per_decade"]))


def linear_bins(spec: dict) -> LinearBins:
    """``LinearBins`` from the config's specification of a bin set.

    Parameters
    ----------
    spec : dict
        The keys lo, hi and width (as in the config's ``simulation`` section).

    Returns
    -------
    LinearBins
    """
    return LinearBins(float(spec["lo"]), float(spec["hi"]), float(spec["width"]))


def log_grid(spec: dict):
    """The points of a logarithmic grid from the config's specification (tables, figures).

    Parameters
    ----------
    spec : dict
        The keys min, max and points.

    Returns
    -------
    numpy.ndarray
        ``numpy.geomspace(min, max, points)``.

    Examples
    --------
    >>> from bouncing_ball.bins import log_grid
    >>> print(log_grid({"min": 0.1, "max": 10.0, "points": 3}))
    [ 0.1  1.  10. ]
    """
    return np.geomspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


def linear_grid(spec: dict):
    """The points of an evenly spaced grid from the config's specification (tables, figures).

    Parameters
    ----------
    spec : dict
        The keys min, max and points.

    Returns
    -------
    numpy.ndarray
        ``numpy.linspace(min, max, points)``.
    """
    return np.linspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(8)


def outgoing_speed_bin_average(density, lower, upper):
    """What a bin of outgoing speeds measures: the flux-weighted bin average of P(0, v).

    Collisions with an outgoing speed in a bin come at the rate int_bin v P(0, v) dv
    (eq. (collrate)), so the simulation's estimate of P(0, v) in a bin [lo, hi) is
    int_lo^hi v P(0, v) dv / int_lo^hi v dv.  8-point Gauss-Legendre in ln v on each bin.

    Parameters
    ----------
    density : callable
        P(0, v) as a function of an array of speeds v > 0.
    lower, upper : array_like
        The finite edges of the bins, 0 < lo < hi.

    Returns
    -------
    numpy.ndarray
        The bin average of each bin.

    Examples
    --------
    For P(0, v) = 1/v the average over [lo, hi) is 2 / (lo + hi):

    >>> import numpy as np
    >>> from bouncing_ball.bins import outgoing_speed_bin_average
    >>> average = outgoing_speed_bin_average(lambda v: 1.0 / v, [0.5, 1.0], [1.0, 3.0])
    >>> print(np.round(average, 12))
    [1.33333333 0.5       ]
    """
    lower = np.asarray(lower, dtype=float)[:, None]
    upper = np.asarray(upper, dtype=float)[:, None]
    half = 0.5 * np.log(upper / lower)
    v = np.exp(half * _GAUSS_NODES[None, :] + 0.5 * np.log(upper * lower))
    flux = half[:, 0] * ((v * v * density(v)) @ _GAUSS_WEIGHTS)
    return flux / (0.5 * (upper[:, 0] ** 2 - lower[:, 0] ** 2))
