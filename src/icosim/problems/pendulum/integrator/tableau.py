"""The constants of Radau IIA (3 stages, order 5) and of its step-size control, as scipy's ``Radau`` has them.

Hairer & Wanner, *Solving ODEs II*, Sect. IV.8; the values are those of scipy's
``integrate/_ivp/radau.py``.  :mod:`.compiled` compiles them into its kernels (numba sees module
globals as constants, so this file is one of :data:`~.kernel_cache.KERNEL_SOURCES`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["C", "E", "MU_REAL", "MU_COMPLEX", "T", "TI", "NEWTON_MAXITER", "MIN_FACTOR", "MAX_FACTOR", "EPS"]

S6 = 6**0.5
#: Collocation nodes of Radau IIA (order 5).
C = np.array([(4 - S6) / 10, (4 + S6) / 10, 1.0])
#: Weights of the embedded error estimate (scipy's ``E``).
E = np.array([-13 - 7 * S6, -13 + 7 * S6, -1]) / 3
#: Eigenvalues of the inverse Butcher matrix: one real, one complex pair.
MU_REAL = 3 + 3 ** (2 / 3) - 3 ** (1 / 3)
MU_COMPLEX = 3 + 0.5 * (3 ** (1 / 3) - 3 ** (2 / 3)) - 0.5j * (3 ** (5 / 6) + 3 ** (7 / 6))
#: Transformation ``A = T diag(...) T^-1`` of the Butcher matrix (scipy's values).
T = np.array(
    [
        [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
        [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
        [1, 1, 0],
    ]
)
#: Its inverse: row 0 gives the real variable, rows 1 and 2 the real and imaginary part of the complex one.
TI = np.array(
    [
        [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
        [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
        [0.50287263494578682, -2.57192694985560522, 0.59603920482822492],
    ]
)

#: Newton iterations per step attempt before the step is halved.
NEWTON_MAXITER = 8
#: Bounds of the step-size factor after a step (scipy's).
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EPS = float(np.finfo(float).eps)
