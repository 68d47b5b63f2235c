"""The error recurrence of :mod:`icosim.studies.convergence.errors` stepped in blocks, and the metrics of a run from it.

``eps_N+1 = M eps_N + D z_N`` is formed block by block: inside a block of ``B`` steps from ``s``,
``eps_s+j = M^j eps_s + G_j z_s``; only the block starts are stepped one by one.  Eq. (72) needs sums of
squares of ``eps`` over step ranges and the growth check a bound of its largest entry: both come from the
block starts and a few matrices per run (:class:`BlockErrors`), not from every ``eps_N``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ErrorSeries", "BlockErrors", "error_recurrence", "error_recurrences"]


class ErrorSeries:
    """The errors ``eps_0 ... eps_N`` of one run, kept in the block layout they are computed in.

    ``blocks[j, :, b]`` is ``eps`` at step ``b * B + j``.  The metrics of
    Eq. (72) are sums of squares over step ranges: :meth:`sum_squares` forms
    them without the (N, n) copy, and :meth:`max_abs` the largest entry;
    :meth:`array` gives the plain ``(N + 1, n)`` array when one is needed.
    """

    def __init__(self, blocks: np.ndarray, n_steps: int):
        self.blocks = blocks
        self.n_steps = int(n_steps)
        self.B = blocks.shape[0]

    @classmethod
    def from_array(cls, errors) -> ErrorSeries:
        errors = np.asarray(errors, dtype=float)
        return cls(errors[:, :, None], errors.shape[0] - 1)

    def array(self) -> np.ndarray:
        n = self.blocks.shape[1]
        return self.blocks.transpose(2, 0, 1).reshape(-1, n)[: self.n_steps + 1]

    def max_abs(self, columns: slice = slice(None)) -> float:
        return float(np.max(self.block_max_abs(columns)))

    def block_max_abs(self, columns: slice = slice(None)) -> np.ndarray:
        """The largest ``|eps_N[columns]|`` of each block over the steps that exist (NaN if one is NaN)."""
        B, nb = self.B, self.blocks.shape[2]
        last = self.n_steps - (nb - 1) * B  # the last block's last step
        with np.errstate(invalid="ignore"):
            out = np.abs(self.blocks[:, columns, : nb - 1]).max(axis=(0, 1)) if nb > 1 else np.empty(0)
            return np.append(out, np.abs(self.blocks[: last + 1, columns, nb - 1]).max())

    def first_step_beyond(self, exact: np.ndarray, bound: float, columns: slice = slice(None)) -> int | None:
        """The first step ``N >= 1`` whose ``max |exact[N - 1] + eps_N[columns]|`` exceeds ``bound`` or is not
        finite, else None (``exact``: the exact values at ``T_1 ... T_N``, the same columns).

        Block by block, in order; a block is skipped when ``max |eps| + max |exact|`` is finite and
        ``<= bound`` (rounding is monotone, so no sum in it can exceed the bound or overflow): the same
        answer as checking every step, with the per-step sums formed only from the first block that could
        cross (a diverging run's early blocks are far below the bound).
        """
        B = self.B
        exact_max = float(np.max(np.abs(exact))) if exact.size else 0.0
        for b, err_max in enumerate(self.block_max_abs(columns)):
            screen = err_max + exact_max
            if np.isfinite(screen) and screen <= bound:  # NaN or an overflow: checked step by step
                continue
            steps = np.arange(max(b * B, 1), min((b + 1) * B, self.n_steps + 1))
            with np.errstate(invalid="ignore"):
                mag = np.max(np.abs(exact[steps - 1] + self.blocks[steps - b * B, columns, b]), axis=-1)
            bad = ~np.isfinite(mag) | (mag > bound)
            if bad.any():
                return int(steps[np.argmax(bad)])
        return None

    def sum_squares(self, columns: slice, first: int, last: int | None = None) -> np.ndarray:
        """``sum_{N = first}^{last} eps_N[columns]^2`` per column (``last`` defaults to the final step)."""
        last = self.n_steps if last is None else min(last, self.n_steps)
        if last < first:
            return np.zeros(self.blocks[:, columns, 0].shape[1])
        sq = np.square(self.blocks[:, columns, :])
        b0, j0 = divmod(first, self.B)
        b1, j1 = divmod(last, self.B)
        if b0 == b1:
            return sq[j0 : j1 + 1, :, b0].sum(axis=0)
        return sq[j0:, :, b0].sum(axis=0) + sq[:, :, b0 + 1 : b1].sum(axis=(0, 2)) + sq[: j1 + 1, :, b1].sum(axis=0)


def _block_size(n_steps: int) -> int:
    """About ``sqrt(n_steps)`` steps: the two sequential loops (``B`` powers, ``n_steps / B`` block starts)
    cost the least.  Part of the result: ``M^B`` carries the run's dominant rounding
    (:func:`error_recurrences`)."""
    return int(np.clip(np.sqrt(n_steps + 1), 16, 2048))


def _segments(lengths: np.ndarray):
    """For lengths sorted in decreasing order: ``(a, first, last)`` with the first ``a`` runs (and only they)
    at least ``j`` long for ``first <= j <= last``, ``j >= 1``."""
    j = 1
    for a in range(len(lengths), 0, -1):
        end = int(lengths[a - 1])
        if end >= j:
            yield a, j, end
            j = end + 1


#: E^j (j < B) by the sequential products of :func:`error_recurrences`, per ``E`` (its bytes): the same
#: ``E`` serves every curve of a step size.
_E_POWERS: dict = {}


def _e_powers(E: np.ndarray, B: int) -> np.ndarray:
    """``E^0 ... E^(B-1)``, ``E^j = E E^(j-1)`` (each product as ``E @ E^(j-1)``); cached per ``E``."""
    key = E.tobytes()
    Ep = _E_POWERS.get(key)
    if Ep is None or Ep.shape[0] < B:
        old = np.eye(2)[None] if Ep is None else Ep
        Ep = np.empty((max(B, 2 * old.shape[0]), 2, 2))
        Ep[: old.shape[0]] = old
        Pl, mm = list(Ep), np.matmul
        for j in range(old.shape[0], Ep.shape[0]):
            mm(E, Pl[j - 1], out=Pl[j])
        if len(_E_POWERS) >= 256:
            _E_POWERS.clear()
        _E_POWERS[key] = Ep
    return Ep[:B]


def error_recurrences(runs, *, blocks=None) -> list[BlockErrors]:
    """:func:`error_recurrence` of several runs with the same state size at once (e.g. the step sizes of one
    curve): ``runs`` lists ``(M, D, E, z_at, n_steps)``.  The same numbers as one run at a time (bit for bit):
    the sequential loops step every run together, one stacked product per step, each item of which is the
    product of the one-run recurrence.
    """
    K = len(runs)
    if K == 0:
        return []
    Ms = np.array([np.asarray(r[0], dtype=float) for r in runs])
    Ds = np.array([np.asarray(r[1], dtype=float) for r in runs])
    N = np.array([int(r[4]) for r in runs])
    blocks = [None] * K if blocks is None else blocks
    Bs = np.array([max(1, min(_block_size(n) if b is None else int(b), n + 1)) for n, b in zip(N, blocks)])
    n = Ms.shape[1]
    mm, add = np.matmul, np.add
    with np.errstate(over="ignore", invalid="ignore"):  # an unstable run grows without bound
        # -- the block matrices: M^j = M M^(j-1), G_j = M G_j-1 + D E^(j-1), j = 1 ... B (runs by decreasing B)
        order = np.argsort(-Bs, kind="stable")
        Bo, Mo = Bs[order], Ms[order]
        Bmax = int(Bo[0])
        DE = np.zeros((Bmax, K, n, 2))
        for i, k in enumerate(order):
            Ep = _e_powers(np.ascontiguousarray(runs[k][2], dtype=float), int(Bo[i]))
            DE[: Bo[i], i] = mm(Ds[k], Ep)  # D E^j, each as D @ E^j
        P = np.empty((Bmax + 1, K, n, n))
        G = np.empty((Bmax + 1, K, n, 2))
        P[0], G[0] = np.eye(n), 0.0
        for a, first, last in _segments(Bo):
            Ma = Mo[:a]
            Pl, Gl, Dl = (
                list(P[first - 1 : last + 1, :a]),
                list(G[first - 1 : last + 1, :a]),
                list(DE[first - 1 : last, :a]),
            )
            for x in range(last + 1 - first):
                mm(Ma, Pl[x], out=Pl[x + 1])
                g = Gl[x + 1]
                mm(Ma, Gl[x], out=g)
                add(g, Dl[x], out=g)
        F, MB, GB = [None] * K, np.empty((K, n, n)), np.empty((K, n, 2))
        for i, k in enumerate(order):
            B = Bo[i]
            F[k] = np.concatenate([P[:B, i], G[:B, i]], axis=2)
            MB[k], GB[k] = P[B, i], G[B, i]
        del P, G, DE
        # -- the block starts: eps_s+B = M^B eps_s + G_B z_s (runs by decreasing number of blocks)
        Z = [np.asarray(r[3](np.arange(0, N[k] + 1, Bs[k])), dtype=float) for k, r in enumerate(runs)]
        nb = np.array([z.shape[0] for z in Z])
        order = np.argsort(-nb, kind="stable")
        nbo = nb[order]
        nbmax = int(nbo[0])
        GZ = np.zeros((nbmax, K, n, 1))
        for i, k in enumerate(order):
            GZ[: nb[k], i] = mm(GB[k], Z[k][:, :, None])  # each G_B z_s as G_B @ z_s
        MBo = MB[order]
        eps = np.empty((nbmax, K, n, 1))  # eps at the block starts (eps_0 = 0)
        eps[0] = 0.0
        for a, first, last in _segments(nbo - 1):
            Ma = MBo[:a]
            El, Gl = list(eps[first - 1 : last + 1, :a]), list(GZ[first - 1 : last, :a])
            for x in range(last + 1 - first):
                e = El[x + 1]
                mm(Ma, El[x], out=e)
                add(e, Gl[x], out=e)
        out = [None] * K
        for i, k in enumerate(order):
            out[k] = BlockErrors(F[k], np.concatenate([eps[: nb[k], i, :, 0], Z[k]], axis=1), N[k])
    return out


def error_recurrence(M, D, E, z_at, n_steps: int, *, block: int | None = None) -> BlockErrors:
    """``eps_0 ... eps_n_steps`` of ``eps_N+1 = M eps_N + D z_N``, ``eps_0 = 0``, as :class:`BlockErrors`:
    the state ``(eps_s, z_s)`` at every block start and the block matrices, from which the metrics are formed
    without forming every ``eps_N`` (:meth:`BlockErrors.materialize` forms them).

    ``z_at(N)`` gives the exact ``z`` at the macro-time points ``N`` (an array
    of step indices; called once, for the block starts).  Inside a block of
    ``B`` steps from ``s``: ``eps_s+j = M^j eps_s + G_j z_s`` with
    ``G_j+1 = M G_j + D E^j``; block starts advance sequentially,
    ``eps_s+B = M^B eps_s + G_B z_s``.  ``B`` defaults to about
    ``sqrt(n_steps)`` (:func:`_block_size`).

    ``M^j = M M^(j-1)``, ``G_j = M G_j-1 + D E^(j-1)`` and the block starts are formed one step at a
    time, by the products of this plain recurrence in this order: the rounding of ``M^B`` and ``G_B``
    is compounded over the ``N / B`` block starts and dominates the rounding of a whole run (~1e-9
    relative in the NRMSE at 10^6 steps, more in the second half of a run whose early error
    dominates), so the block starts are kept bit for bit, and the block algebra around them
    (:class:`BlockErrors`) moves a run's NRMSE by ~1e-15 (measured on every curve of Figs. 21-23; 3e-11
    for ``nrmse_lambda``, whose terms cancel most).
    """
    return error_recurrences([(M, D, E, z_at, n_steps)], blocks=[block])[0]


#: Bounds of :meth:`BlockErrors.block_bounds` are widened by this factor: it covers the rounding of the
#: bound's sum of positive terms and of any float64 product forming an error (both below 1e-14 relative
#: for up to a few hundred terms), so a screened block cannot hold a larger computed error.
_BOUND_SLACK = 1.0 + 1e-12


#: A block's sum of squares comes from the QR factor (:class:`BlockErrors`) only where its terms cancel by
#: less than this (``sum_k |F[:, c, k]| |s_k|``, 2-norms over the block's steps, over the root of the sum): its
#: rounding is then below ~30 u times this (measured), 4e-11 relative.  The same rounding in every block (one
#: factor for all) adds up over the blocks, where that of steps formed one by one partly cancels: blocks that
#: cancel more (the coupling variables of index 3, errors of 1e-20 in a part of the state) are formed step
#: by step, for that column.
QR_MAX_CANCELLATION = 1e4


class BlockErrors:
    """The errors ``eps_0 ... eps_N`` of one run as block starts and block matrices (not formed one by one).

    ``eps`` at step ``b * B + j`` is ``F[j] @ S[b]``: ``S[b] = (eps_s, z_s)`` the error and the exact
    ``z`` at the block start ``s = b * B``, ``F[j] = [M^j | G_j]``.  The metrics need sums of squares over
    step ranges and bounds on the largest entry, both cheaper than the steps:

    * over a whole block, ``sum_j (F[j, c] @ s)^2 = |R_c s|^2`` with ``R_c`` (``(n + 2)`` square) the
      triangular factor of the QR decomposition of the ``B`` rows ``F[:, c]`` -- one QR per column, then
      ``O(n^2)`` per block instead of ``O(B n^2)``.  Householder QR is column-wise backward stable and
      ``R_c s`` is a short product: the rounding is relative to the terms of ``F[j, c] @ s``, as for the
      steps themselves (not to their squares, as for a Gram matrix ``F^T F``); where those terms cancel by
      more than :data:`QR_MAX_CANCELLATION`, the block's steps are formed for that column.  Steps of a
      range that do not fill a block are formed one by one.
    * every ``|eps_N[c]|`` of block ``b`` is at most ``|S[b]| @ max_j |F[j, c]|`` (a bound for the
      computed errors as well: :data:`_BOUND_SLACK`): a block this clears needs no steps formed.
    """

    def __init__(self, F: np.ndarray, S: np.ndarray, n_steps: int):
        self.F = F  # (B, n, n + 2)
        self.S = S  # (blocks, n + 2)
        self.n_steps = int(n_steps)
        self.B = F.shape[0]
        self.n = F.shape[1]
        self._sums = {}  # column -> |R_c S[b]|^2 of the blocks that lie inside the run
        self._bounds = {}  # columns (tuple) -> per-block bounds

    def _columns(self, columns) -> np.ndarray:
        return np.arange(self.n)[columns]

    @property
    def n_full(self) -> int:
        """Blocks whose every step lies in the run."""
        return (self.n_steps + 1) // self.B

    def rows(self, b: int, j0: int, j1: int) -> np.ndarray:
        """``eps`` at the steps ``b * B + j0 ... b * B + j1`` (inclusive), shape ``(j1 - j0 + 1, n)``."""
        m = self.F.shape[2]
        with np.errstate(over="ignore", invalid="ignore"):
            return (self.F[j0 : j1 + 1].reshape(-1, m) @ self.S[b]).reshape(-1, self.n)

    def materialize(self) -> ErrorSeries:
        """Every ``eps_N`` in :class:`ErrorSeries`'s block layout (each block as :meth:`rows` forms it)."""
        blocks = [self.rows(b, 0, self.B - 1) for b in range(self.S.shape[0])]
        return ErrorSeries(np.stack(blocks, axis=-1), self.n_steps)

    def array(self) -> np.ndarray:
        return self.materialize().array()

    def max_abs(self, columns: slice = slice(None)) -> float:
        """The largest computed ``|eps_N[columns]|`` (every step formed: for checks; see :meth:`max_abs_bound`)."""
        return self.materialize().max_abs(columns)

    # -- sums of squares ----------------------------------------------------------------------------------
    def _block_sums(self, cols) -> np.ndarray:
        """``sum_j eps[b * B + j, c]^2`` of every block inside the run (``n_full`` rows), per column of ``cols``.

        From the QR factor where the block's terms cancel little (:data:`QR_MAX_CANCELLATION`), else
        from the block's steps, formed for that column only.
        """
        missing = [c for c in cols if c not in self._sums]
        if missing:
            nf, m = self.n_full, self.F.shape[2]
            S = self.S[:nf]
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                Fc = np.ascontiguousarray(self.F[:, missing, :].transpose(1, 0, 2))  # (columns, B, n + 2)
                R = np.linalg.qr(Fc, mode="r")
                r = R.shape[1]
                sums = np.square(S @ R.reshape(-1, m).T).reshape(nf, len(missing), r).sum(axis=-1)
                # sum_k |F[:, c, k]| |s_k| over the block (2-norms over its steps) against the result's root
                scale = np.abs(S) @ np.sqrt(np.square(Fc).sum(axis=1)).T
                redo = ~(scale <= QR_MAX_CANCELLATION * np.sqrt(sums))
            for i, c in enumerate(missing):
                b = np.flatnonzero(redo[:, i])
                if b.size:
                    with np.errstate(over="ignore", invalid="ignore"):
                        sums[b, i] = np.square(Fc[i] @ S[b].T).sum(axis=0)
                self._sums[c] = sums[:, i]
        return np.stack([self._sums[c] for c in cols], axis=-1)

    def sum_squares(self, columns: slice, first: int, last: int | None = None) -> np.ndarray:
        """``sum_{N = first}^{last} eps_N[columns]^2`` per column (``last`` defaults to the final step)."""
        cols = self._columns(columns)
        last = self.n_steps if last is None else min(last, self.n_steps)
        if last < first:
            return np.zeros(cols.size)
        B = self.B
        if first == 1 and not np.any(self.S[0, : self.n]):
            first = 0  # eps_0 = F[0] @ S[0] = 0 exactly: the block from step 0 is whole
        b0, j0 = divmod(first, B)
        b1, j1 = divmod(last, B)
        pieces = []  # (block, first row, last row) formed step by step
        if b0 == b1 and not (j0 == 0 and j1 == B - 1):
            pieces.append((b0, j0, j1))
            whole = (0, 0)
        else:
            lo, hi = b0, b1 + 1  # the whole blocks lo ... hi - 1
            if j0 > 0:
                pieces.append((b0, j0, B - 1))
                lo += 1
            if j1 < B - 1:
                pieces.append((b1, 0, j1))
                hi -= 1
            whole = (lo, hi)
        with np.errstate(over="ignore", invalid="ignore"):
            total = np.zeros(cols.size)
            if whole[1] > whole[0]:
                total = total + self._block_sums(cols)[whole[0] : whole[1]].sum(axis=0)
            for b, ja, jb in pieces:
                total = total + np.square(self.rows(b, ja, jb)[:, cols]).sum(axis=0)
        return total

    # -- bounds and the first step beyond a bound -----------------------------------------------------------
    def block_bounds(self, columns: slice = slice(None)) -> np.ndarray:
        """Per block an upper bound of every computed ``|eps_N[columns]|`` in it (NaN or inf: none)."""
        key = tuple(self._columns(columns))
        if key not in self._bounds:
            F = self.F[:, columns, :] if isinstance(columns, slice) else self.F[:, list(key), :]
            with np.errstate(over="ignore", invalid="ignore"):
                A = np.abs(F).max(axis=0)  # (columns, n + 2)
                X = np.abs(self.S) @ A.T
                # the largest per block, column by column (a reduction over the short axis costs more)
                bound = X[:, 0].copy()
                for c in range(1, X.shape[1]):
                    np.maximum(bound, X[:, c], out=bound)
                self._bounds[key] = bound * _BOUND_SLACK
        return self._bounds[key]

    def max_abs_bound(self, columns: slice = slice(None)) -> float:
        """An upper bound of the largest computed ``|eps_N[columns]|`` (NaN or inf if it cannot be bounded)."""
        bounds = self.block_bounds(columns)
        return float(np.max(bounds))

    def first_step_beyond(
        self, exact, bound: float, columns: slice = slice(None), *, exact_max: float | None = None
    ) -> int | None:
        """The first step ``N >= 1`` whose ``max |exact[N - 1] + eps_N[columns]|`` exceeds ``bound`` or is not
        finite, else None (as :meth:`ErrorSeries.first_step_beyond`).

        ``exact``: the exact values at ``T_1 ... T_N`` (same columns), or a function of an array of steps
        ``N`` giving them (then ``exact_max``, the largest ``|exact|``, is required).  A block is skipped when
        its bound (:meth:`block_bounds`) plus ``max |exact|`` is finite and ``<= bound``; the steps of the
        others are formed, in order, until one crosses.
        """
        if callable(exact):
            if exact_max is None:
                raise ValueError("exact_max is required with an exact function")
            values = exact
        else:
            exact = np.asarray(exact, dtype=float)
            exact_max = float(np.max(np.abs(exact))) if exact.size else 0.0
            values = lambda steps: exact[steps - 1]  # noqa: E731
        cols = self._columns(columns)
        B = self.B
        with np.errstate(over="ignore", invalid="ignore"):
            screen = self.block_bounds(columns) + exact_max
        for b in np.flatnonzero(~(np.isfinite(screen) & (screen <= bound))):
            lo, hi = max(b * B, 1), min((b + 1) * B, self.n_steps + 1)  # the steps lo ... hi - 1
            if hi <= lo:
                continue
            steps = np.arange(lo, hi)
            with np.errstate(over="ignore", invalid="ignore"):
                eps = self.rows(b, lo - b * B, hi - 1 - b * B)[:, cols]
                mag = np.max(np.abs(values(steps) + eps), axis=-1)
            bad = ~np.isfinite(mag) | (mag > bound)
            if bad.any():
                return int(steps[np.argmax(bad)])
        return None
