"""Physical units: the paper's results for any gravity g and noise strength Lambda.

The equation of motion, eq. (eqmo), d^2x/dt^2 = -g + eta(t) with
<eta(t) eta(t')> = 2 Lambda delta(t - t'), holds two constants; the paper sets g = Lambda = 1
"since this can be achieved by rescaling of x and t" (its footnote [rescale]).  The rescaling
is by the only length and time the two constants make,

    length L = Lambda^2 / g^3,    time T = Lambda / g^2,    speed V = L / T = Lambda / g,

(g has the dimension of a speed per time, Lambda of a speed squared per time), so that every
quantity with length dimension a and time dimension b is its dimensionless value times
L^a T^b: <x> and Delta x (a = 1) by g^-3 Lambda^2 and I (b = -1) by g^2 Lambda^-1, as the
paper's closing paragraph says.  r is dimensionless, and so are the exponents beta, m and the
bounce counts; the decay rate q of eq. (asym4) is per speed (V^-1).  The weight function
w(F) of eq. (weightfunc) is per square root of a length: P(x) of eq. (P(x)1) is
int dF F^(-1/2) w(F) exp(-1/(12F) - F x), a density per length with F per length.

``DIMENSIONS`` lists (a, b) of every quantity the library returns or takes, by name, and
``PhysicalUnits`` converts.
"""

import math
import numbers
from dataclasses import dataclass

import numpy as np

__all__ = ["DIMENSIONS", "PhysicalUnits"]

#: (length power a, time power b) of each quantity: its value in physical units is the paper's
#: dimensionless value times L^a T^b (``PhysicalUnits.factor``).
DIMENSIONS = {
    "dimensionless": (0, 0),
    "length": (1, 0),  # x, <x>, Delta x
    "length_squared": (2, 0),  # <x^2>
    "time": (0, 1),  # T, <T>, the relaxation time
    "time_squared": (0, 2),  # <T^2>
    "speed": (1, -1),  # v, u
    "speed_squared": (2, -2),  # <v^2>_x
    "rate": (0, -1),  # I, and a density per unit time (rho(T))
    "per_length": (-1, 0),  # P(x), and the force variable F of eq. (weightfunc)
    "per_speed": (-1, 1),  # a density per unit speed (the return-speed law), q of eq. (asym4)
    "phase_space_density": (-2, 1),  # P(x, v), P(0, v): per unit length and speed
    "rate_per_time": (0, -2),  # the flight-rate density nu(T) = I rho(T)
    # w(F) of eq. (weightfunc): P(x) = int dF F^(-1/2) w(F) exp(-1/(12F) - F x), eq. (P(x)1),
    # with P(x) per length and F per length, so w(F) is per square root of a length
    "per_root_length": (-0.5, 0),
}


def _positive(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    number = float(value)
    if not 0.0 < number < math.inf:
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return number


@dataclass(frozen=True)
class PhysicalUnits:
    """The units of a bouncing ball with gravity g and noise strength Lambda, eq. (eqmo).

    Parameters
    ----------
    gravity : float, optional
        g > 0, finite: the constant acceleration toward the floor (e.g. 9.81 for m/s^2).
    noise : float, optional
        Lambda > 0, finite: the strength of the random force, <eta(t) eta(t')> =
        2 Lambda delta(t - t') (a speed squared per time, e.g. m^2/s^3): the variance of the
        velocity grows by 2 Lambda per unit time under the noise alone.

    Raises
    ------
    TypeError
        If gravity or noise is not a real number (a bool included).
    ValueError
        If gravity or noise is not positive and finite, or the two make a unit of some
        dimension of ``DIMENSIONS`` (L^a T^b) that is not a finite, normal double (g and
        Lambda many decades from 1 in opposite directions).

    Attributes
    ----------
    length, time, speed : float
        L = Lambda^2 / g^3, T = Lambda / g^2 and V = Lambda / g: one paper unit of each.

    Examples
    --------
    >>> from bouncing_ball.units import PhysicalUnits
    >>> units = PhysicalUnits(gravity=9.81, noise=0.05)
    >>> print(f"{units.length:.4e} {units.time:.4e} {units.speed:.4e}")
    2.6481e-06 5.1956e-04 5.0968e-03
    >>> print(f"{units.to_physical(1.0, 'length'):.4e}")  # <x> of 1 paper unit, in metres
    2.6481e-06
    >>> PhysicalUnits().factor("rate")
    1.0
    """

    gravity: float = 1.0
    noise: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "gravity", _positive(self.gravity, "gravity"))
        object.__setattr__(self, "noise", _positive(self.noise, "noise"))
        smallest = np.finfo(float).tiny
        for dimension in DIMENSIONS:
            try:
                factor = self.factor(dimension)
            except (OverflowError, ZeroDivisionError):
                factor = math.nan
            if not smallest <= factor < math.inf:
                raise ValueError(
                    f"gravity = {self.gravity!r} and noise = {self.noise!r} make a unit "
                    f"(L^a T^b of DIMENSIONS[{dimension!r}], L = noise^2 / gravity^3, "
                    f"T = noise / gravity^2) that is not a finite, normal double: the values "
                    "converted would be lost"
                )

    @property
    def length(self) -> float:
        return self.noise**2 / self.gravity**3

    @property
    def time(self) -> float:
        return self.noise / self.gravity**2

    @property
    def speed(self) -> float:
        return self.noise / self.gravity

    @property
    def is_paper(self) -> bool:
        """Whether g = Lambda = 1, the paper's units (every factor is exactly 1)."""
        return self.gravity == 1.0 and self.noise == 1.0

    def factor(self, dimension: str) -> float:
        """L^a T^b for ``dimension``, a key of ``DIMENSIONS``.

        Parameters
        ----------
        dimension : str
            A key of ``DIMENSIONS``.

        Returns
        -------
        float
            The physical value of one paper unit of that quantity.

        Raises
        ------
        KeyError
            If ``dimension`` is not a key of ``DIMENSIONS``.
        """
        try:
            a, b = DIMENSIONS[dimension]
        except KeyError:
            raise KeyError(
                f"dimension {dimension!r}: one of {', '.join(sorted(DIMENSIONS))}"
            ) from None
        return self.length**a * self.time**b

    def to_physical(self, value, dimension: str):
        """A paper-unit ``value`` (a number or an array) in these units.

        Parameters
        ----------
        value : float or numpy.ndarray
            In the paper's units, g = Lambda = 1.
        dimension : str
            A key of ``DIMENSIONS``.

        Returns
        -------
        float or numpy.ndarray
            ``value`` times ``factor(dimension)`` (``value`` itself in the paper's units).
        """
        return value if self.is_paper else value * self.factor(dimension)

    def to_paper(self, value, dimension: str):
        """A ``value`` in these units (a number or an array) in the paper's units.

        Parameters
        ----------
        value : float or numpy.ndarray
            In these units.
        dimension : str
            A key of ``DIMENSIONS``.

        Returns
        -------
        float or numpy.ndarray
            ``value`` divided by ``factor(dimension)`` (``value`` itself in the paper's units).
        """
        return value if self.is_paper else value / self.factor(dimension)
