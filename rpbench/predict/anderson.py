"""Type-II Anderson mixing for the fixed-point iteration (Walker & Ni 2011), with an updated QR factorisation.

Each step solves ``γ = argmin ||ΔF γ - f||`` over the last ``depth``
residual differences and returns ``β f - (ΔX + β ΔF) γ`` in place of the
damped step ``β f``.  On the month table ΔF has about 10^6 rows and at most
5 columns, and factorising it afresh every step (``numpy.linalg.lstsq``, an
SVD after a Householder QR, plus stacking the columns) took 0.18 s a step,
3 s of a prediction.  Here ``ΔF = Q R`` is kept up to date instead, as Walker
and Ni do: a new column is orthogonalised against Q twice (classical
Gram-Schmidt with one re-orthogonalisation, orthogonal to working precision),
the oldest is dropped with Givens rotations on R and Q, and the small
problem ``min ||R γ - Qᵀ f||`` is solved with the same SVD cut-off numpy's
``lstsq`` applies to ΔF (singular values below ``eps · rows`` times the
largest count as zero, so a history whose differences have become
collinear gives the minimum-norm γ, not an exploding one).  R has ΔF's
singular values, so the cut-off is the same; only the rounding differs.
"""

from __future__ import annotations

import numpy as np


class AndersonMixing:
    """Anderson mixing over the last ``depth`` iterates; :meth:`step` returns the accelerated step."""

    def __init__(self, depth: int) -> None:
        self.depth = depth
        self._q: np.ndarray | None = None        # (n, depth), Fortran order: column j is q_j
        self._dx: np.ndarray | None = None       # (n, depth) ring of ΔX columns
        self._r = np.zeros((depth, depth))
        self.restart()

    def restart(self) -> None:
        """Forget the history (the next step is the damped one)."""
        self.x_prev = self.f_prev = None
        self.size = 0                           # columns in the history
        self._slots: list[int] = []             # ring slot of ΔX's column j, oldest first

    def step(self, x: np.ndarray, f: np.ndarray, damped: np.ndarray, beta: float) -> np.ndarray:
        """The step from iterate ``x`` with residual ``f = g(x) - x`` (``damped = β f``)."""
        if self.x_prev is not None:
            self._append(x - self.x_prev, f - self.f_prev)
        self.x_prev, self.f_prev = x, f
        if self.size == 0:
            return damped
        try:
            gamma = self.coefficients(f)
        except np.linalg.LinAlgError:           # the SVD of a non-finite history does not converge
            gamma = np.full(self.size, np.nan)
        if not np.all(np.isfinite(gamma)):
            self.restart()
            return damped
        m = self.size
        df_gamma = self._q[:, :m] @ (self._r[:m, :m] @ gamma)
        weights = np.zeros(self.depth)
        weights[self._slots] = gamma
        return damped - self._dx @ weights - beta * df_gamma

    def coefficients(self, f: np.ndarray) -> np.ndarray:
        """``γ = argmin ||ΔF γ - f||`` (minimum norm, numpy's default ``lstsq`` cut-off on ΔF)."""
        m = self.size
        rcond = np.finfo(np.float64).eps * max(len(f), m)
        gamma, *_ = np.linalg.lstsq(self._r[:m, :m], self._q[:, :m].T @ f, rcond=rcond)
        return gamma

    def _append(self, dx: np.ndarray, df: np.ndarray) -> None:
        if self._q is None or self._q.shape[0] != len(df):
            self._q = np.zeros((len(df), self.depth), order="F")
            self._dx = np.zeros((len(df), self.depth), order="F")
        if self.size == self.depth:
            self._drop_oldest()
        slot = next(k for k in range(self.depth) if k not in self._slots)
        self._dx[:, slot] = dx
        self._slots.append(slot)
        self._add_column(df)

    def _add_column(self, v: np.ndarray) -> None:
        """Append ``v`` to ΔF = QR: two rounds of Gram-Schmidt against Q, then normalise."""
        m = self.size
        q = self._q[:, :m]
        r = np.zeros(m)
        v = np.array(v, dtype=np.float64)
        for _ in range(2):
            if m:
                h = q.T @ v
                v -= q @ h
                r += h
        norm = float(np.linalg.norm(v))
        self._r[:m, m] = r
        self._r[m, m] = norm
        self._r[m + 1:, m] = 0.0
        self._q[:, m] = v / norm if norm > 0.0 else 0.0
        self.size = m + 1

    def _drop_oldest(self) -> None:
        """Remove ΔF's first column: R without it is upper Hessenberg; Givens rotations restore it."""
        m = self.size
        r = self._r
        r[:m, :m - 1] = r[:m, 1:m].copy()
        r[:, m - 1] = 0.0
        q = self._q
        for k in range(m - 1):
            a, b = r[k, k], r[k + 1, k]
            h = float(np.hypot(a, b))
            if h == 0.0:
                continue
            c, s = a / h, b / h
            rk, rk1 = r[k, k:m - 1].copy(), r[k + 1, k:m - 1].copy()
            r[k, k:m - 1] = c * rk + s * rk1
            r[k + 1, k:m - 1] = c * rk1 - s * rk
            r[k + 1, k] = 0.0
            qk = q[:, k].copy()
            q[:, k] *= c
            q[:, k] += s * q[:, k + 1]
            q[:, k + 1] *= c
            q[:, k + 1] -= s * qk
        r[m - 1, :] = 0.0
        self._slots.pop(0)                      # its ΔX slot is reused by the next column
        self.size = m - 1
