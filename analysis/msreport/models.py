"""Closed-form curves drawn beside measurements (dense curves between measured angles).

The C++ models (include/microsim/models/ndf.hpp) are the reference; these few formulas are
repeated here only to draw smooth lines. Each cites its source equation.
"""
import math

import numpy as np


def beckmann_lambda(a):
    """001 Sec. 3.2 (Beckmann Lambda): (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi))."""
    a = np.asarray(a, dtype=float)
    out = np.zeros_like(a)
    pos = a > 0
    erf = np.vectorize(math.erf)
    out[pos] = 0.5 * (erf(a[pos]) - 1.0) + np.exp(-a[pos] ** 2) / (2.0 * a[pos] * math.sqrt(math.pi))
    out[~pos] = np.inf
    return out


def ggx_lambda(a):
    """001 Sec. 3.2-3.3 (GGX Lambda): (-1 + sqrt(1 + 1/a^2)) / 2."""
    a = np.asarray(a, dtype=float)
    with np.errstate(divide="ignore"):
        return 0.5 * (-1.0 + np.sqrt(1.0 + 1.0 / a ** 2))


def alpha_o(alpha_x, alpha_y, phi):
    """001 eq. (11): projected roughness along the view azimuth."""
    return np.sqrt(np.cos(phi) ** 2 * alpha_x ** 2 + np.sin(phi) ** 2 * alpha_y ** 2)


def smith_g1(kind, alpha_x, alpha_y, theta, phi=0.0):
    """Smith G1(v) = 1 / (1 + Lambda(a)), a = 1 / (alpha_o tan theta) (001 eq. 10-11)."""
    theta = np.asarray(theta, dtype=float)
    ao = alpha_o(alpha_x, alpha_y, phi)
    with np.errstate(divide="ignore"):
        a = 1.0 / (ao * np.tan(theta))
    lam = beckmann_lambda(a) if kind == "beckmann" else ggx_lambda(a)
    lam = np.where(theta <= 0, 0.0, lam)
    return 1.0 / (1.0 + lam)


def beckmann_d(alpha, theta_m):
    """Isotropic Beckmann D(m) = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) (001 Sec. 3.2)."""
    theta_m = np.asarray(theta_m, dtype=float)
    c = np.cos(theta_m)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = np.exp(-np.tan(theta_m) ** 2 / alpha ** 2) / (math.pi * alpha ** 2 * c ** 4)
    return np.where(c > 0, d, 0.0)


def ggx_d(alpha, theta_m):
    """Isotropic GGX D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2) (001 Sec. 3.3, isotropic)."""
    theta_m = np.asarray(theta_m, dtype=float)
    c = np.cos(theta_m)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = alpha ** 2 / (math.pi * c ** 4 * (alpha ** 2 + np.tan(theta_m) ** 2) ** 2)
    return np.where(c > 0, d, 0.0)
