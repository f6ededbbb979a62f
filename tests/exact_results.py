"""The paper's exact results that tests hold the code to, written out independently of it."""

from fractions import Fraction

import numpy as np

# eq. (xandDeltax) in closed form: <x>, Delta x and I at r = 1/2 and 1/3
TIME_AVERAGES = {
    Fraction(1, 2): {"mean_x": 6.0, "delta_x": 6.0 * np.sqrt(3.0), "collision_rate": 1.0 / 3.0},
    Fraction(1, 3): {
        "mean_x": 35.0 / 9.0,
        "delta_x": np.sqrt(4781.0) / 9.0,
        "collision_rate": 0.75,
    },
}
