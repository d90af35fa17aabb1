"""Closed-form curves drawn beside measurements (dense curves between measured angles).

Evaluated by the Python module's models (microsim.models, the C++ code of
include/microsim/models/), so the report draws exactly the library's theory. The module is built
with the project (build/python); PYTHONPATH=build/python, or the default build folder is found.
"""
import os
import sys

import numpy as np

try:
    import microsim
except ImportError:  # a run from the source tree after `cmake --build build`
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "build", "python"))
    try:
        import microsim
    except ImportError as e:
        raise ImportError("the report needs the Python module microsim: build the project "
                          "(cmake --build build) and set PYTHONPATH=build/python") from e

M = microsim.models


def beckmann_lambda(a):
    """[Heitz14, sec. 3.2] (Beckmann Lambda): (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)); +inf for a <= 0."""
    return M.beckmann_lambda(np.asarray(a, dtype=float))


def ggx_lambda(a):
    """[Heitz14, sec. 3.2-3.3] (GGX Lambda): (-1 + sqrt(1 + 1/a^2)) / 2."""
    return M.ggx_lambda(np.asarray(a, dtype=float))


def smith_g1(kind, alpha_x, alpha_y, theta, phi=0.0):
    """Smith G1(v) = 1 / (1 + Lambda(v)) of the nominal NDF [Heitz14, eq. 10-11], theta and phi in radians."""
    return M.NDF(kind, alpha_x, alpha_y).G1(M.direction(np.asarray(theta, dtype=float), phi))


def _isotropic_d(kind, alpha, theta_m):
    m = M.direction(np.asarray(theta_m, dtype=float), 0.0)
    return np.asarray(M.NDF(kind, alpha).D(m))


def beckmann_d(alpha, theta_m):
    """Isotropic Beckmann D(m) = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) [Heitz14, sec. 3.2]."""
    return _isotropic_d("beckmann", alpha, theta_m)


def ggx_d(alpha, theta_m):
    """Isotropic GGX D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2) [Heitz14, sec. 3.3] (isotropic)."""
    return _isotropic_d("ggx", alpha, theta_m)
