"""An independent reference for period-1 impacting orbits, written from Eq. (1) alone.

Between impacts x'' + 2 (c/m) x' + (k/m) x = cos(omega t) / m has the closed form
x = x_p + h with x_p = A cos(omega t) + B sin(omega t), A = (k - m omega^2) / D,
B = 2 c omega / D, D = (k - m omega^2)^2 + (2 c omega)^2, and h a damped free
oscillation (underdamped case only: the tests use c^2 < k m).  A 1-impact period-1 orbit
leaves the wall (x = g) at tau with speed r u and is back on it at tau + T with velocity
-u; its impact map (tau, u) -> (tau', u') is found by scanning for the first crossing and
brentq.  Nothing here calls impactlib.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, root


def flight(p, t0, x0, v0, t):
    """(x, v) at times t of the free flight from (x0, v0) at t0 (underdamped)."""
    m, c, k, w = p.m, p.c, p.k, p.omega
    D = (k - m * w * w) ** 2 + (2 * c * w) ** 2
    A, B = (k - m * w * w) / D, 2 * c * w / D
    a = c / m
    b = math.sqrt(k / m - a * a)
    h0 = x0 - (A * math.cos(w * t0) + B * math.sin(w * t0))
    hv0 = v0 - w * (-A * math.sin(w * t0) + B * math.cos(w * t0))
    s = np.asarray(t, dtype=float) - t0
    e = np.exp(-a * s)
    C, S = np.cos(b * s), np.sin(b * s)
    c2 = (hv0 + a * h0) / b
    h = e * (h0 * C + c2 * S)
    hv = e * (-a * (h0 * C + c2 * S) + (-h0 * b * S + c2 * b * C))
    t = np.asarray(t, dtype=float)
    return (A * np.cos(w * t) + B * np.sin(w * t) + h,
            w * (-A * np.sin(w * t) + B * np.cos(w * t)) + hv)


def residual(p, z):
    """Period-1 residual: leave (g, r u) at tau, arrive at (g, -u) at tau + T."""
    tau, u = z
    x, v = flight(p, tau, p.g, p.r * u, tau + p.T)
    return [float(x) - p.g, float(v) + u]


def admissible(p, tau, u, n=4000):
    """No crossing of the wall between the impacts (sampled densely)."""
    ts = np.linspace(tau, tau + p.T, n)[1:-1]
    x, _ = flight(p, tau, p.g, p.r * u, ts)
    return bool(np.all(x > p.g))


def period1_orbits(p):
    """Admissible 1-impact period-1 orbits (tau in [0, T), u > 0), from a grid of guesses."""
    found = []
    for tau0 in np.linspace(0, p.T, 24, endpoint=False):
        for u0 in (0.2, 0.5, 1.0, 2.0):
            sol = root(lambda z: residual(p, z), [tau0, u0], tol=1e-14)
            if not sol.success:
                continue
            tau, u = sol.x
            tau = tau % p.T
            if u <= 1e-6 or max(abs(np.asarray(residual(p, (tau, u))))) > 1e-11:
                continue
            if not admissible(p, tau, u):
                continue
            if all(abs(tau - f[0]) > 1e-8 or abs(u - f[1]) > 1e-8 for f in found):
                found.append((tau, u))
    return found


def impact_map(p, tau, u):
    """Next impact (tau', u') after leaving the wall at tau with speed r u."""
    w = p.T / 400
    lo = tau + 1e-9 * p.T
    x_lo = flight(p, tau, p.g, p.r * u, lo)[0] - p.g
    for i in range(1, 2000):
        hi = tau + i * w
        x_hi = flight(p, tau, p.g, p.r * u, hi)[0] - p.g
        if x_hi < 0 < x_lo:
            t1 = brentq(lambda t: flight(p, tau, p.g, p.r * u, t)[0] - p.g, lo, hi, xtol=1e-15,
                        rtol=1e-15)
            return t1, -float(flight(p, tau, p.g, p.r * u, t1)[1])
        lo, x_lo = hi, x_hi
    raise RuntimeError("no impact within 2000 steps")


def multipliers(p, tau, u, h=1e-6):
    """Eigenvalues of the impact map's Jacobian at a period-1 orbit, by central differences."""
    J = np.empty((2, 2))
    for j, (dt, du) in enumerate(((h, 0.0), (0.0, h))):
        a = impact_map(p, tau + dt, u + du)
        b = impact_map(p, tau - dt, u - du)
        J[:, j] = [(a[0] - b[0]) / (2 * h), (a[1] - b[1]) / (2 * h)]
    return np.linalg.eigvals(J)


def section_point(p, tau, u, phase=0.0):
    """The orbit's state at the first section time phase + n T after the impact at tau."""
    ts = phase + p.T * math.ceil((tau - phase) / p.T)
    if ts <= tau:
        ts += p.T
    x, v = flight(p, tau, p.g, p.r * u, ts)
    return float(x), float(v)
