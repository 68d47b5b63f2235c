"""The links' equations in numpy: the independent reference of the compiled ones.

The package evaluates the links' right-hand sides and outputs in the compiled kernels
(:mod:`icosim.problems.pendulum.integrator.compiled_links`: loops over scalars, numba).  These are the same
equations written with numpy arrays, as methods of the links (:class:`NumpyLink1`, :class:`NumpyLink2`, the
package's :class:`~icosim.problems.pendulum.links.Link1` and ``Link2`` with them): each provides the
right-hand side for an input polynomial (force ``lambda`` or joint acceleration ``a_tilde``) and its outputs at
the joint (position, velocity, acceleration and the joint force it sees).  Equations in docs/pendulum.md.
:mod:`reference_radau` integrates them; tests compare.
"""

from __future__ import annotations

import numpy as np

from icosim.problems.pendulum.links import Link1, Link2

__all__ = ["NumpyLink1", "NumpyLink2", "numpy_links"]


def numpy_links(links):
    """The numpy counterparts of a problem's links."""
    return tuple((NumpyLink1 if isinstance(link, Link1) else NumpyLink2)(link.p, link.kind) for link in links)


def _poly(coef, tau):
    """``sum_m coef[:, m, :] tau^m`` (Horner); ``coef`` (B, K, n_u), ``tau`` broadcasts to (..., B)."""
    tau = np.asarray(tau, dtype=float)[..., None]
    u = coef[:, -1, :]
    for m in range(coef.shape[1] - 2, -1, -1):
        u = u * tau + coef[:, m, :]
    return u


class NumpyLink1(Link1):
    """Link 1 pinned to ground: state ``(phi1, omega1)``; its right-hand side and outputs in numpy."""

    def _torque_ext(self, phi, w):
        p = self.p
        return -p.m1 * p.g * p.l1 / 2 * np.cos(phi) - p.d * p.l1**2 / 4 * w

    def accel(self, Y, u):
        p = self.p
        phi, w = Y[..., 0], Y[..., 1]
        c, s = np.cos(phi), np.sin(phi)
        tangential = c * u[..., 1] - s * u[..., 0]  # n1 . u
        if self.kind == "force":
            return (self._torque_ext(phi, w) - p.l1 * tangential) / p.JO1
        return tangential / p.l1

    def rhs(self, coef, H):
        def fun(t, Y):
            u = _poly(coef, np.asarray(t) / H)
            alpha = self.accel(Y, u)
            out = np.empty(alpha.shape + (2,))
            out[..., 0] = Y[..., 1]
            out[..., 1] = alpha
            return out

        return fun

    def outputs(self, Y, f, u):
        """``(P, P', P'', f)`` of the joint point, shape (B, 4, 2)."""
        p = self.p
        phi, w, alpha = Y[..., 0], Y[..., 1], f[..., 1]
        e = _unit(phi)
        nrm = _normal(e)
        out = np.empty(np.broadcast_shapes(phi.shape, u.shape[:-1]) + (4, 2))
        out[..., 0, :] = p.l1 * e
        out[..., 1, :] = p.l1 * w[..., None] * nrm
        out[..., 2, :] = p.l1 * alpha[..., None] * nrm - p.l1 * (w * w)[..., None] * e
        if self.kind == "force":
            out[..., 3, :] = u
        else:  # tangential joint force that realises l1 phi1'' = n1 . a_tilde
            mu1 = (self._torque_ext(phi, w) - p.JO1 * alpha) / p.l1
            out[..., 3, :] = mu1[..., None] * nrm
        return out


class NumpyLink2(Link2):
    """Free link 2: state ``(x_S2, y_S2, phi2, vx, vy, omega2)``; its right-hand side and outputs in numpy."""

    def rhs(self, coef, H):
        """``(v, a_S, phi2'')`` for the input ``u`` (force lambda or joint acceleration a_tilde)."""
        p = self.p
        l2h = p.l2 / 2
        if self.kind == "force":

            def fun(t, Y):
                u = _poly(coef, np.asarray(t) / H)
                c, s = np.cos(Y[..., 2]), np.sin(Y[..., 2])
                ux, uy = u[..., 0], u[..., 1]
                out = np.empty(np.broadcast_shapes(Y.shape[:-1], u.shape[:-1]) + (6,))
                out[..., 0:3] = Y[..., 3:6]
                out[..., 3] = (ux - p.d * Y[..., 3]) / p.m2
                out[..., 4] = (uy - p.d * Y[..., 4]) / p.m2 - p.g
                out[..., 5] = -l2h * (c * uy - s * ux) / p.J2
                return out

        else:
            inertia = p.J2 + p.m2 * l2h**2

            def fun(t, Y):
                u = _poly(coef, np.asarray(t) / H)
                c, s = np.cos(Y[..., 2]), np.sin(Y[..., 2])
                w = Y[..., 5]
                ux, uy = u[..., 0], u[..., 1]
                Fx = -p.d * Y[..., 3]
                Fy = -p.m2 * p.g - p.d * Y[..., 4]
                # (J + m l^2/4) phi2'' = (l/2) e2 x F - (m l/2) e2 x a_tilde
                alpha = l2h * ((c * Fy - s * Fx) - p.m2 * (c * uy - s * ux)) / inertia
                ww = w * w
                out = np.empty(np.broadcast_shapes(Y.shape[:-1], u.shape[:-1]) + (6,))
                out[..., 0:3] = Y[..., 3:6]
                # a_S = a_tilde + (l/2)(phi2'' n2 - omega2^2 e2)
                out[..., 3] = ux + l2h * (-alpha * s - ww * c)
                out[..., 4] = uy + l2h * (alpha * c - ww * s)
                out[..., 5] = alpha
                return out

        return fun

    def _force_ext(self, Y):
        p = self.p
        return np.stack([-p.d * Y[..., 3], -p.m2 * p.g - p.d * Y[..., 4]], axis=-1)

    def outputs(self, Y, f, u):
        p = self.p
        phi, w, alpha = Y[..., 2], Y[..., 5], f[..., 5]
        e = _unit(phi)
        nrm = _normal(e)
        out = np.empty(np.broadcast_shapes(phi.shape, u.shape[:-1]) + (4, 2))
        out[..., 0, :] = Y[..., 0:2] - p.l2 / 2 * e
        out[..., 1, :] = Y[..., 3:5] - p.l2 / 2 * w[..., None] * nrm
        out[..., 2, :] = f[..., 3:5] - p.l2 / 2 * (alpha[..., None] * nrm - (w * w)[..., None] * e)
        out[..., 3, :] = u if self.kind == "force" else self.p.m2 * f[..., 3:5] - self._force_ext(Y)
        return out


def _unit(phi):
    """``(cos phi, sin phi)`` on a new last axis."""
    e = np.empty(np.shape(phi) + (2,))
    np.cos(phi, out=e[..., 0])
    np.sin(phi, out=e[..., 1])
    return e


def _normal(e):
    """``e`` turned by +90 degrees: ``(-e_y, e_x)``."""
    n = np.empty(e.shape)
    np.negative(e[..., 1], out=n[..., 0])
    n[..., 1] = e[..., 0]
    return n
