"""Type-II Anderson mixing for the fixed-point iteration (Walker & Ni 2011), with an updated QR factorisation.

Each step solves ``γ = argmin ||ΔF γ - f||`` over the last ``depth``
residual differences and returns ``β f - (ΔX + β ΔF) γ`` in place of the
damped step ``β f``.  On the month table ΔF has about 10^6 rows and at most
5 columns; factorising it afresh every step (an SVD after a Householder QR,
plus stacking the columns) costs about 0.2 s a step, so ``ΔF = Q R`` is kept
up to date instead, as Walker and Ni do: a new column is orthogonalised
against Q twice (classical Gram-Schmidt with one re-orthogonalisation,
orthogonal to working precision); the oldest is dropped with Givens
rotations on R, applied to Q as one small matrix product; and ``min ||R γ - Qᵀ f||`` is solved with the
SVD cut-off numpy's ``lstsq`` applies to ΔF (singular values below
``eps · rows`` times the largest count as zero, so a history whose
differences have become collinear gives the minimum-norm γ, not an exploding
one).  R has ΔF's singular values, so the cut-off is the same; only the
rounding differs.  The differences are written straight into preallocated
column buffers: a step is about 20 passes over a vector, 0.02-0.06 s on the
month table.
"""

from __future__ import annotations

import numpy as np

#: A new column whose part outside the others' span is below this share of its norm is treated as dependent.
DEPENDENT = 1e-3


class AndersonMixing:
    """Anderson mixing over the last ``depth`` iterates; :meth:`step` returns the accelerated step."""

    def __init__(self, depth: int) -> None:
        self.depth = depth
        # Column buffers, allocated at the first step for its length n (empty until then):
        self._dx = np.zeros((0, depth), order="F")  # (n, depth), Fortran order: a ring of ΔX columns
        self._q = np.zeros((0, depth), order="F")  # (n, depth), Fortran order: q_0 .. q_{size-1}
        self._q_spare = np.zeros((0, depth), order="F")  # where the next drop writes Q (then the two swap)
        self._r = np.zeros((depth, depth))
        self.x_prev: np.ndarray | None = None
        self.f_prev: np.ndarray | None = None
        self.restart()

    def restart(self) -> None:
        """Forget the history (the next step is the damped one)."""
        self.x_prev = self.f_prev = None
        self.size = 0  # columns in the history
        self._slots: list[int] = []  # ring slot of ΔX's column j, oldest first

    def step(self, x: np.ndarray, f: np.ndarray, damped: np.ndarray, beta: float) -> np.ndarray:
        """The step from iterate ``x`` with residual ``f = g(x) - x`` (``damped = β f``)."""
        if self.x_prev is not None:
            self._append(x, f)
        self.x_prev, self.f_prev = x, f
        if self.size == 0:
            return damped
        try:
            gamma = self.coefficients(f)
        except np.linalg.LinAlgError:  # the SVD of a non-finite history does not converge
            gamma = np.full(self.size, np.nan)
        if not np.all(np.isfinite(gamma)):
            self.restart()
            return damped
        m = self.size
        weights = np.zeros(self.depth)
        weights[self._slots] = gamma
        out = damped - self._dx @ weights  # - ΔX γ
        out -= self._q[:, :m] @ (beta * (self._r[:m, :m] @ gamma))  # - β ΔF γ, ΔF = QR
        return out

    def coefficients(self, f: np.ndarray) -> np.ndarray:
        """``γ = argmin ||ΔF γ - f||`` (minimum norm, numpy's default ``lstsq`` cut-off on ΔF)."""
        m = self.size
        rcond = np.finfo(np.float64).eps * max(len(f), m)
        gamma, *_ = np.linalg.lstsq(self._r[:m, :m], self._q[:, :m].T @ f, rcond=rcond)
        return gamma

    def _append(self, x: np.ndarray, f: np.ndarray) -> None:
        assert self.x_prev is not None and self.f_prev is not None
        n = len(f)
        if self._q.shape[0] != n:
            self._dx, self._q, self._q_spare = (np.zeros((n, self.depth), order="F") for _ in range(3))
        if self.size == self.depth:
            self._drop_oldest()
        slot = next(k for k in range(self.depth) if k not in self._slots)
        np.subtract(x, self.x_prev, out=self._dx[:, slot])
        self._slots.append(slot)
        np.subtract(f, self.f_prev, out=self._q[:, self.size])
        self._orthogonalise_last()

    def _orthogonalise_last(self) -> None:
        """Column ``size`` of Q holds a new ΔF column: two rounds of Gram-Schmidt against Q, then normalise.

        A column (almost) in the span of the others leaves only rounding noise,
        which two rounds do not make orthogonal to Q: normalised, it would break
        QᵀQ = I (by 3e-7 in a test).  Such a remainder, or an exact zero, is
        replaced by a unit vector orthogonalised afresh, with the remainder's
        norm (tiny or 0) as its R entry: ΔF = QR still holds to rounding, Q
        stays orthonormal, and the SVD cut-off drops that direction.
        """
        m = self.size
        q, v = self._q[:, :m], self._q[:, m]
        scale = float(np.linalg.norm(v))
        r = self._gram_schmidt(q, v)
        norm = float(np.linalg.norm(v))
        if norm > DEPENDENT * scale:
            v /= norm
        else:
            if norm > 0.0:
                v /= norm
            else:  # an exact repeat: any direction outside Q will do
                v[:] = np.random.default_rng(m).standard_normal(len(v))
            self._gram_schmidt(q, v)
            v /= np.linalg.norm(v)
        self._r[:m, m] = r
        self._r[m, m] = norm
        self._r[m + 1 :, m] = 0.0
        self.size = m + 1

    @staticmethod
    def _gram_schmidt(q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Two rounds of classical Gram-Schmidt of ``v`` against the columns of ``q``, in place; the coefficients."""
        r = np.zeros(q.shape[1])
        if q.shape[1]:
            for _ in range(2):
                h = q.T @ v
                v -= q @ h
                r += h
        return r

    def _drop_oldest(self) -> None:
        """Remove ΔF's first column: R without it is upper Hessenberg; Givens rotations restore it.

        The rotations are collected in one m x m orthogonal matrix G (R <- G R), and
        Q <- Q Gᵀ is one matrix product instead of two vector updates per rotation.
        """
        m = self.size
        r = self._r
        r[:m, : m - 1] = r[:m, 1:m].copy()
        r[:, m - 1] = 0.0
        g = np.eye(m)
        for k in range(m - 1):
            a, b = r[k, k], r[k + 1, k]
            h = float(np.hypot(a, b))
            if h == 0.0:
                continue
            c, s = a / h, b / h
            rotation = np.array([[c, s], [-s, c]])
            r[k : k + 2, k : m - 1] = rotation @ r[k : k + 2, k : m - 1]
            r[k + 1, k] = 0.0
            g[k : k + 2, :] = rotation @ g[k : k + 2, :]
        r[m - 1, :] = 0.0
        np.matmul(self._q[:, :m], g[: m - 1, :].T, out=self._q_spare[:, : m - 1])
        self._q, self._q_spare = self._q_spare, self._q
        self._slots.pop(0)  # its ΔX slot is reused by the next column
        self.size = m - 1
