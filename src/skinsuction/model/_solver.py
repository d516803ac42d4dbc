"""The solver of the suction test: Newton's method with tangent reuse, load
increments with an extrapolated predictor and cutback, the sparse factorisation of
the tangents, and the failure of an increment."""

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import splu

from ._fast import _SUPERLU_OPTIONS, OrderedFactors

__all__ = ["NoEquilibrium", "Stepping", "TangentFactorizer", "newton", "reach"]


def _factorize(K):
    # MMD on A^T+A in symmetric mode: the tangent is symmetric in pattern and in
    # value. SuperLU's default threshold (1.0) still swaps rows for any larger
    # off-diagonal entry, which wrecks the symmetric ordering (3-4x the fill); the
    # tangent of a stable equilibrium is positive definite, so diagonal pivots are
    # kept unless one is below a tenth of its column's largest entry
    return splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", options=_SUPERLU_OPTIONS)


class TangentFactorizer:
    """Factorises the tangents of one model, computing the fill-reducing order once.

    SuperLU orders the matrix anew at every factorisation; for these tangents
    (2-3 k DOFs) the minimum-degree ordering is about a sixth of it (8.4 -> 7.2 ms
    on a 2 670-DOF ray tangent). The sparsity pattern of a model's tangent hardly
    changes (the tangent at rest lacks a few entries), so the order SuperLU found
    is kept and each later tangent is permuted symmetrically into it and
    factorised in its natural order: the same fill and pivots. Any symmetric
    permutation is a valid order, so a changed pattern costs fill, never
    correctness; the order is recomputed when the number of entries changes.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> K = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(6, 6)).tocsr()
    >>> factorize = TangentFactorizer(np.arange(6))
    >>> b = np.ones(6)
    >>> x1, x2 = factorize(K).solve(b), factorize(K).solve(b)  # ordered, then reused
    >>> bool(np.allclose(K @ x1, b) and np.allclose(K @ x2, b))
    True
    """

    def __init__(self, free_dofs):
        self.free = np.asarray(free_dofs)
        self._rows = None  # free DOFs in the kept order
        self._nnz = -1

    def __call__(self, K):
        K = K.tocsr()
        if self._rows is not None:
            A = K[self._rows][:, self._rows]
            if A.nnz == self._nnz:
                lu = splu(A.tocsc(), permc_spec="NATURAL", options=_SUPERLU_OPTIONS)
                return OrderedFactors(lu, self._order)
        A = K[self.free][:, self.free]  # in the model's own order: SuperLU orders it anew
        lu = _factorize(A)
        self._order = np.argsort(lu.perm_c)
        self._rows, self._nnz = self.free[self._order], A.nnz
        return lu


class NoEquilibrium(RuntimeError):
    """Newton's method found no equilibrium for one pressure increment."""

    def __init__(self, message, iterations=0):
        super().__init__(message)
        self.iterations = iterations


def newton(model, lu, tol, maxiter, f, floor=0.0, xtol=1e-9, stall_after=8,
           stall_window=4, keep_fresh=False):
    """Newton's method at the current load, in place on the displacement field.

    The factorised tangent ``lu`` (of an earlier increment, if given) serves
    while it cuts the residual tenfold an iteration; otherwise, and from the
    third iteration on, the tangent is refactorised (full Newton). A step
    that inverts an element (non-finite residual) is halved before it is
    accepted. An increment whose residual has not halved in ``stall_window``
    iterations, after ``stall_after``, is given up (the caller cuts it back).

    Parameters
    ----------
    model : SuctionTest
        The model, at its current load (its ``_residual`` and ``_tangent``).
    lu : factors or None
        A tangent to start with.
    tol : float
        Residual of the free DOFs relative to the reactions (floored by
        ``floor``: a time step after a release, where both vanish).
    maxiter : int
        Iterations before :class:`NoEquilibrium` is raised.
    f : ndarray
        The residual of the current state.
    floor : float
        Smallest reaction norm the criterion divides by.
    xtol : float
        A correction below ``xtol`` of the displacement also ends it.
    stall_after, stall_window : int
        The stall rule above.
    keep_fresh : bool
        A tangent of this increment also serves from the third iteration on,
        while it contracts tenfold (a time step: the last step's tangent is close,
        one of this step's closer; one factorisation a step instead of 1.8, the
        same history to the tolerance). Off for load increments, whose full
        Newton from the third iteration on the space's rays were solved with.

    Returns
    -------
    (factors, int, ndarray)
        The tangent in use, the iterations spent and the final residual.
    """
    u = model.field[0].values.reshape(-1)
    history = []  # residual norms of this increment's iterations
    fresh = False  # lu is a tangent of this increment
    for iteration in range(1, maxiter + 1):
        if not np.all(np.isfinite(f)):
            raise NoEquilibrium("an element is inverted", iteration - 1)
        r1 = f[model.dof1]
        norm_r1 = np.linalg.norm(r1)
        if norm_r1 <= tol * max(np.linalg.norm(f[model.dof0]), floor):
            return lu, iteration - 1, f
        history.append(norm_r1)
        # full Newton from the 3rd iteration on contracts a sound increment
        # quadratically; one that has not halved its residual in 4 of them
        # wanders (a limit point, an element about to invert): a smaller
        # increment is cheaper than the rest of maxiter
        if iteration > stall_after and norm_r1 > 0.5 * min(history[:-stall_window]):
            raise NoEquilibrium(
                f"no contraction in {stall_window} iterations", iteration - 1
            )
        # an earlier tangent serves while it contracts the residual tenfold: a
        # factorisation costs six modified iterations on the fast path, and a
        # tangent that contracts less wastes more than it saves (measured:
        # 1.7x less CPU over 28 rays than reuse while halving, to the 5th
        # iteration)
        stale = iteration > 2 and not (keep_fresh and fresh)
        if lu is None or stale or (iteration > 1 and norm_r1 > 0.1 * history[-2]):
            lu, fresh = model._tangent(), True
        du = lu.solve(-r1)
        u_start = u[model.dof1].copy()
        for _ in range(6):
            u[model.dof1] = u_start + du
            f = model._residual()
            if np.all(np.isfinite(f)):
                break
            du *= 0.5
        # when the loads are tiny against the moduli, the residual stalls at its
        # round-off floor first: then a negligible correction means converged
        if np.all(np.isfinite(f)) and np.linalg.norm(du) <= xtol * np.linalg.norm(u_start + du):
            return lu, iteration, f
    raise NoEquilibrium(f"no convergence in {maxiter} iterations", maxiter)


@dataclass
class Stepping:
    """Where a run stands: the last two equilibria, pressure, increments, tangent."""

    u_now: np.ndarray
    u_before: np.ndarray
    dp: float
    nominal: float
    p_now: float = 0.0
    dp_last: float = 0.0
    iterations: int = 0
    lu: object = None


def reach(model, target, state, tol, maxiter, min_increment_mbar, iteration_budget,
           stall_after):
    """Increments of ``model`` from ``state.p_now`` up to the output pressure
    ``target``, with an extrapolated predictor and cutback; ``state`` moves along.

    Parameters
    ----------
    model : SuctionTest
    target : float
        The output pressure (mbar).
    state : Stepping
    tol, maxiter, stall_after
        Of :func:`newton`.
    min_increment_mbar : float
        Smallest increment tried before giving up.
    iteration_budget : int
        Newton iterations of the whole run before giving up.

    Returns
    -------
    str
        Why it stopped short ("" if it reached ``target``).
    """
    u = model.field[0].values
    while state.p_now < target - 1e-12:
        if state.iterations > iteration_budget:
            return (f"no equilibrium above {state.p_now:g} mbar (iteration budget of "
                    f"{iteration_budget} spent)")
        remaining = target - state.p_now
        if remaining <= 1e-6 * state.nominal:
            # round-off of the sum of cut-back increments: the equilibrium is
            # this pressure's to 1e-6 of an increment (a solve here would also
            # make the next increment start from this sliver)
            state.p_now = target
            return ""
        clipped = remaining <= state.dp
        step = remaining if clipped else state.dp
        p_next = target if clipped else state.p_now + step
        # linear extrapolation of the last converged increment, unless it
        # inverts an element (then Newton starts from the last equilibrium)
        scale = step / state.dp_last if state.dp_last > 0 else 0.0
        u[:] = state.u_now + scale * (state.u_now - state.u_before)
        model._set_pressure(p_next)
        with np.errstate(all="ignore"):
            f = model._residual()
        if not np.all(np.isfinite(f)):
            u[:], f = state.u_now, None
        try:
            with np.errstate(all="ignore"):
                state.lu, used = model._equilibrium(p_next, state.lu, tol, maxiter, f=f,
                                                   stall_after=stall_after)
            state.iterations += used
            if used > 2:
                # a hard increment: its last tangent would mislead the next
                state.lu = None
        except (NoEquilibrium, RuntimeError, ValueError, np.linalg.LinAlgError) as err:
            # the budget counts the iterations spent, not the ones allowed
            state.iterations += getattr(err, "iterations", maxiter)
            state.lu, state.dp = None, step / 4
            if state.dp < min_increment_mbar:
                return (f"no equilibrium above {state.p_now:g} mbar (increment cut "
                        f"back below {min_increment_mbar:g} mbar: {err})")
            continue
        model._commit()
        state.u_before, state.u_now = state.u_now, u.copy()
        state.p_now, state.dp_last = p_next, step
        # an increment cut short by an output pressure says nothing of the
        # increment size: it stays (doubling from a sliver would creep)
        if not clipped:
            state.dp = min(2 * state.dp, state.nominal)
    return ""
