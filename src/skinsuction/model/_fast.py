"""The fast path: residual and tangent of this one model, assembled by NumPy.

FElupe assembles any body from any material through general integral forms:
81 components of a 3x3x3x3 elasticity tensor, sparse sums of items, a
reduction ``K[dof1][:, dof1]`` and a conversion to CSC at every iteration.
This model needs far less, and this module does only that:

* the axisymmetric deformation gradient has 5 components (``F_zz, F_zr,
  F_rz, F_rr`` and the hoop stretch), so the elasticity is a 5x5 matrix per
  Gauss point;
* element matrices go straight into the data array of the free-DOF tangent,
  in a fill-reducing order chosen once, through an index map built once (the
  sparsity pattern never changes: every coupling of a cell is kept, zero or
  not);
* the suction is a follower pressure on a chain of 3-node edges of the skin
  surface, integrated by 3-point Gauss (exact for its degree-5 integrand);
* the probe wall is a frictionless penalty on the radial DOF of the surface
  nodes that pass ``r = a``.

FElupe builds the mesh, the quadrature, the shape-function gradients and the
boundary conditions; :class:`skinsuction.model.SuctionTest` with
``engine="felupe"`` keeps FElupe's own assembly, and ``tests/test_fast.py``
checks that both give the same residual and tangent to 1e-10.
"""

from __future__ import annotations

import numpy as np
import qdldl
import scipy.sparse as sp
from scipy.sparse.linalg import splu

#: The in-plane and hoop components of F in FElupe's axisymmetric order
#: (0: axial z, 1: radial r, 2: hoop).
COMPONENTS = ((0, 0), (0, 1), (1, 0), (1, 1), (2, 2))

# MMD on A^T+A in symmetric mode: the tangent is symmetric in pattern and in value.
# SuperLU's default threshold (1.0) still swaps rows for any larger off-diagonal
# entry, which wrecks the symmetric ordering (3-4x the fill); diagonal pivots are
# kept unless one is below a tenth of its column's largest entry
_SUPERLU_OPTIONS = {"SymmetricMode": True, "DiagPivotThresh": 0.1}

# S[P, Q] = iFT[i, L] iFT[k, J] for P = (i, J), Q = (k, L): index into the
# 6-vector (iFT_zz, iFT_zr, iFT_rz, iFT_rr, iFT_hoop, 0) of the block-diagonal iFT
_FULL = {c: n for n, c in enumerate(COMPONENTS)}
SWAP = np.array([[_FULL.get((i, L), 5) * 6 + _FULL.get((k, J), 5)
                   for (k, L) in COMPONENTS] for (i, J) in COMPONENTS])


def material_response(f, x1, x2, bulk, f0=None, tangent=True):
    """First Piola-Kirchhoff stress (5, n) and elasticity (5, 5, n) of
    ``W = X1 (I1bar - 3) + X2 (I1bar - 3)^2 + K/2 (J - 1)^2`` at the 5 components
    ``f`` (5, n) of F at n points; ``f0`` (5, n): the columns' pre-stretch factors."""
    if f0 is not None:
        f = f * f0
    a, b, c, d, h = f
    det2 = a * d - b * c
    J = det2 * h
    # iFT = cof(F) / J, block-diagonal
    ift = np.stack([d / det2, -c / det2, -b / det2, a / det2, 1.0 / h])
    I1 = np.einsum("pn,pn->n", f, f)
    G = J ** (-2.0 / 3.0)
    W1 = x1 + 2.0 * x2 * (G * I1 - 3.0)
    dI1bar = G * (2.0 * f - 2.0 / 3.0 * I1 * ift)
    P = W1 * dI1bar + bulk * (J - 1.0) * J * ift
    if f0 is not None:
        P = P * (f0 / np.prod(f0[[0, 3, 4]], axis=0))
    if not tangent:
        return P, None
    c1 = W1 * G * 4.0 / 9.0 * I1 + bulk * (2.0 * J - 1.0) * J
    c2 = W1 * G * 2.0 / 3.0 * I1 - bulk * (J - 1.0) * J
    beta = -4.0 / 3.0 * W1 * G
    ext = np.concatenate([ift, np.zeros((1,) + ift.shape[1:])])
    swap = (ext[:, None] * ext[None, :]).reshape(36, -1)[SWAP]
    A = c1 * ift[:, None] * ift[None, :] + c2 * swap
    B = beta * f[:, None] * ift[None, :]
    A += B + B.transpose(1, 0, 2)
    A += 2.0 * x2 * dI1bar[:, None] * dI1bar[None, :]
    A[np.arange(5), np.arange(5)] += 2.0 * W1 * G
    if f0 is not None:
        A = A * (f0[:, None] * f0[None, :] / np.prod(f0[[0, 3, 4]], axis=0))
    return P, A


class FastAssembly:
    """Residual and free-DOF tangent of the suction-test model (see the module).

    Parameters
    ----------
    region : felupe.Region
        The quadratic quad region of the skin (quad8 or quad9, any quadrature).
    x1, x2, bulk : ndarray
        Per-cell parameters (MPa).
    prestretch : ndarray or None
        Per-cell diagonal of the pre-deformation F0, shape (3, ncells), in
        FElupe's axisymmetric order (axial, radial, hoop).
    suction_edges : ndarray of int, shape (m, 3)
        Surface edges under suction: corner, midside, corner node.
    wall_points : ndarray of int
        Surface nodes that may touch the probe wall ``r = wall_radius``.
    wall_radius : float
    free : ndarray of int
        Free DOFs (FElupe's ``dof1``), of ``npoints * 2``.
    npoints : int
        Points of the mesh (the probe's reference point included).

    Examples
    --------
    See :class:`skinsuction.model.SuctionTest` (``engine="fast"``, the default).
    """

    def __init__(self, region, x1, x2, bulk, prestretch, suction_edges, wall_points,
                 wall_radius, free, npoints, wall_center=None, solver="qdldl"):
        mesh = region.mesh
        self.points = np.asarray(mesh.points, dtype=float)
        self.cells = np.asarray(mesh.cells)
        ncells, nn = self.cells.shape
        self.ndof = 2 * npoints
        h = np.broadcast_to(region.h, region.h.shape[:2] + (ncells,))  # (nn, q, c)
        dhdX = region.dhdX  # (nn, 2, q, c)
        R = np.einsum("aqc,ac->qc", h, mesh.points[self.cells, 1].T)
        self.weight = 2.0 * np.pi * R * region.dV  # (q, c)
        # B: d(5 components of F) / d(element DOFs), per Gauss point: (c, q, 2 nn, 5)
        nq = R.shape[0]
        B = np.zeros((ncells, nq, nn, 2, 5))
        dh = dhdX.transpose(3, 2, 0, 1)  # (c, q, a, J)
        for p, (i, J) in enumerate(COMPONENTS[:4]):
            B[:, :, :, i, p] = dh[..., J]
        B[:, :, :, 1, 4] = (h / R).transpose(2, 1, 0)
        # Gauss points flattened cell by cell: (c q, 2 nn, 5), and B^T
        self.nq = nq
        self.B = np.ascontiguousarray(B.reshape(ncells * nq, 2 * nn, 5))
        self.Bw = self.B * self.weight.T.reshape(-1, 1, 1)
        self.BT = np.ascontiguousarray(self.B.transpose(0, 2, 1))

        def per_point(x):
            return np.repeat(np.broadcast_to(np.asarray(x, float), (ncells,)), nq)

        self.x1, self.x2, self.bulk = per_point(x1), per_point(x2), per_point(bulk)
        self.f0 = None
        if prestretch is not None:
            F0 = np.asarray(prestretch, float).reshape(3, -1)
            # the factor of column J of F_iJ, per component
            self.f0 = np.repeat(F0[[0, 1, 0, 1, 2]], nq, axis=1)
        self.eldofs = (2 * self.cells[:, :, None] + np.arange(2)).reshape(ncells, -1)

        self.suction_edges = np.asarray(suction_edges, dtype=int).reshape(-1, 3)
        xi, wq = np.polynomial.legendre.leggauss(3)
        # quadratic line shape functions (corner, midside, corner) and derivatives
        self._line_h = np.stack([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2])
        self._line_dh = np.stack([xi - 0.5, -2 * xi, xi + 0.5])
        self._line_w = wq
        self.edge_dofs = (2 * self.suction_edges[:, :, None] + np.arange(2)).reshape(-1, 6)

        self.wall_points = np.asarray(wall_points, dtype=int)
        self.wall_radius = float(wall_radius)
        self.wall_center = wall_center
        self.wall_multiplier = 0.0

        self.free = np.asarray(free)
        self._pattern()
        self.solid_diagonal = None
        if solver not in ("qdldl", "superlu"):
            raise ValueError(f"solver must be 'qdldl' or 'superlu', not {solver!r}")
        self.solver = solver
        self._qdldl, self._upper_slots = None, None

    # ---------------------------------------------------------------- sparsity
    def _pattern(self):
        """CSC structure of the free-DOF tangent, in a fill-reducing order found
        once, and the map from element-matrix entries to its data array."""
        n = self.free.size
        index = np.full(self.ndof, -1)
        index[self.free] = np.arange(n)
        k = self.eldofs.shape[1]
        rows = np.repeat(index[self.eldofs], k, axis=1).ravel()
        cols = np.tile(index[self.eldofs], k).ravel()
        keep = (rows >= 0) & (cols >= 0)
        rows, cols = rows[keep], cols[keep]
        # minimum degree on A^T + A once (SuperLU would redo it at every
        # factorisation); a dominant diagonal makes the pattern's matrix regular
        pattern = sp.csc_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
        lu = splu(pattern + n * sp.identity(n, format="csc"),
                  permc_spec="MMD_AT_PLUS_A", options=_SUPERLU_OPTIONS)
        self.order = np.argsort(lu.perm_c)  # order[k]: the free DOF in position k
        rank = np.empty(n, dtype=int)
        rank[self.order] = np.arange(n)
        self.position = np.full(self.ndof, -1)  # global DOF -> position in the kept order
        self.position[self.free] = rank
        keys = rank[cols].astype(np.int64) * n + rank[rows]
        self._keys, self.slot = np.unique(keys, return_inverse=True)  # column-major slots
        self.indices = (self._keys % n).astype(np.int32)
        self.indptr = np.searchsorted(self._keys // n, np.arange(n + 1)).astype(np.int32)
        self.keep = np.flatnonzero(keep)
        self.nnz = self._keys.size

    def _slots(self, row_dofs, col_dofs):
        """Data slots of the entries (row DOF, column DOF); -1 where either is fixed."""
        rows, cols = self.position[row_dofs], self.position[col_dofs]
        free = (rows >= 0) & (cols >= 0)
        out = np.full(rows.shape, -1)
        out[free] = np.searchsorted(self._keys, cols[free].astype(np.int64) * self.free.size
                                    + rows[free])
        return out

    # -------------------------------------------------------------- kinematics
    def _components(self, u):
        """The 5 components of F (5, c q) from the displacements (npoints, 2)."""
        ue = np.repeat(u.reshape(-1)[self.eldofs], self.nq, axis=0)  # (c q, 2 nn)
        grad = (ue[:, None, :] @ self.B)[:, 0, :].T.copy()
        grad[[0, 3, 4]] += 1.0
        return grad

    # ---------------------------------------------------------------- residual
    def residual(self, u, pressure):
        """Residual (internal minus external forces) of every DOF, ``(2 npoints,)``.

        ``pressure`` is FElupe's (positive pushes inwards; suction is negative).
        """
        f = self._components(u)
        with np.errstate(invalid="ignore", divide="ignore"):
            P, _ = material_response(f, self.x1, self.x2, self.bulk, self.f0, tangent=False)
            added = self._added_stress(f, tangent=False)
        if added is not None:
            P = P + added[0]
        re = (self.Bw @ P.T[:, :, None]).reshape(-1, self.nq, self.B.shape[1]).sum(axis=1)
        r = np.bincount(self.eldofs.ravel(), re.ravel(), minlength=self.ndof)
        if pressure != 0.0 and len(self.suction_edges):
            fe, _ = self._suction(u, pressure, tangent=False)
            r += np.bincount(self.edge_dofs.ravel(), fe.ravel(), minlength=self.ndof)
        if self.wall_multiplier and len(self.wall_points):
            gap, dofs = self._wall_gap(u)
            active = gap < 0
            force = -self.wall_multiplier * gap[active]
            np.add.at(r, dofs[active], force)
            if self.wall_center is not None:  # the probe's reaction
                r[2 * self.wall_center + 1] -= force.sum()
        return r

    # ----------------------------------------------------------------- tangent
    def tangent(self, u, pressure):
        """Data array of the free-DOF tangent in the kept order (CSC, ``nnz``)."""
        f = self._components(u)
        P, A = material_response(f, self.x1, self.x2, self.bulk, self.f0)
        A = np.ascontiguousarray(A.transpose(2, 0, 1))  # (c q, 5, 5)
        added = self._added_stress(f, tangent=True)
        if added is not None:
            A += added[1]
        nx = self.B.shape[1]
        Ke = ((self.Bw @ A) @ self.BT).reshape(-1, self.nq, nx, nx).sum(axis=1)
        # the solid's diagonal at the wall points' radial DOFs, for the penalty
        if len(self.wall_points):
            diag = np.bincount(self.eldofs.ravel(), np.einsum("cxx->cx", Ke).ravel(),
                               minlength=self.ndof)
            self.solid_diagonal = diag[2 * self.wall_points + 1]
        data = np.bincount(self.slot, Ke.ravel()[self.keep], minlength=self.nnz)
        if pressure != 0.0 and len(self.suction_edges):
            _, ke = self._suction(u, pressure, tangent=True)
            data += self._edge_contribution(ke)
        if self.wall_multiplier and len(self.wall_points):
            gap, dofs = self._wall_gap(u)
            slots = self._wall_slots()
            active = (gap < 0) & (slots >= 0)
            np.add.at(data, slots[active], self.wall_multiplier)
        return data

    def _added_stress(self, f, tangent):
        """A stress added to the layers' law at the Gauss points: ``(P (5, c q), A (c q,
        5, 5) or None)``, or None (none here; the viscous branches' history adds one)."""
        return None

    def matrix(self, data):
        """The tangent as a CSC matrix in the kept order."""
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.free.size,) * 2)

    def factorize(self, data):
        """Factors of the tangent, solving in the model's free-DOF order.

        QDLDL's LDL^T of the upper triangle, with the symbolic factorisation
        of the first call kept (the tangent is symmetric: the follower pressure's
        stiffness is, once assembled over free DOFs, since the loaded surface
        ends at the axis and at the glued face); SuperLU's LU where QDLDL meets
        a zero pivot or ``solver="superlu"``.
        """
        if self.solver == "qdldl":
            upper = self._upper(data)
            try:
                if self._qdldl is None:
                    self._qdldl = qdldl.Solver(upper, upper=True)
                else:
                    self._qdldl.update(upper, upper=True)
                return OrderedFactors(self._qdldl, self.order)
            except ValueError:
                self._qdldl = None  # a zero pivot: rebuilt from the next tangent
        lu = splu(self.matrix(data), permc_spec="NATURAL", options=_SUPERLU_OPTIONS)
        return OrderedFactors(lu, self.order)

    def _upper(self, data):
        if self._upper_slots is None:
            A = self.matrix(np.arange(1, self.nnz + 1, dtype=float))
            U = sp.triu(A, format="csc")
            U.sort_indices()
            self._upper_slots = U.data.astype(int) - 1
            self._upper_indices, self._upper_indptr = U.indices, U.indptr
        return sp.csc_matrix((data[self._upper_slots], self._upper_indices, self._upper_indptr),
                             shape=(self.free.size,) * 2)

    # ----------------------------------------------------------------- suction
    def _suction(self, u, pressure, tangent):
        """Follower pressure on the edges: forces (m, 6) and matrices (m, 6, 6)."""
        x = (self.points + u.reshape(-1, 2))[self.suction_edges]  # (m, 3 nodes, 2)
        h, dh, w = self._line_h, self._line_dh, self._line_w
        xq = np.einsum("aq,mai->mqi", h, x)
        dx = np.einsum("aq,mai->mqi", dh, x)
        r = xq[..., 1]
        # n da = 2 pi r (dr, -dz) dxi, outwards for edges run from the axis outwards
        normal = np.stack([dx[..., 1], -dx[..., 0]], axis=-1)
        scale = pressure * 2.0 * np.pi * w
        fe = np.einsum("aq,mq,mqi->mai", h, scale * r, normal).reshape(-1, 6)
        if not tangent:
            return fe, None
        # d(r n)/dx_b,k = N_b e_r (x) n + r dN_b Q, Q = [[0, 1], [-1, 0]]
        Q = np.array([[0.0, 1.0], [-1.0, 0.0]])
        ke = np.einsum("aq,bq,mq,mqi->maib", h, h, np.broadcast_to(scale, r.shape), normal)
        K = np.zeros((len(x), 3, 2, 3, 2))
        K[..., 1] = ke
        K += np.einsum("aq,bq,mq,ik->maibk", h, dh, scale * r, Q)
        return fe, K.reshape(-1, 6, 6)

    def _edge_contribution(self, ke):
        if not hasattr(self, "_edge_slot"):
            # an edge's couplings are its cell's: every one has a slot
            slot = self._slots(np.repeat(self.edge_dofs, 6, axis=1).ravel(),
                               np.tile(self.edge_dofs, 6).ravel())
            self._edge_slot, self._edge_keep = slot[slot >= 0], np.flatnonzero(slot >= 0)
        return np.bincount(self._edge_slot, ke.ravel()[self._edge_keep], minlength=self.nnz)

    # -------------------------------------------------------------------- wall
    def _wall_gap(self, u):
        radial = self.points[self.wall_points, 1] + u.reshape(-1, 2)[self.wall_points, 1]
        return self.wall_radius - radial, 2 * self.wall_points + 1

    def _wall_slots(self):
        if not hasattr(self, "_wall_slot"):
            radial = 2 * self.wall_points + 1
            self._wall_slot = self._slots(radial, radial)
        return self._wall_slot

    def update_wall_multiplier(self, penalty):
        """FElupe's stiffness-based multiplier: ``penalty`` times the mean radial
        stiffness of the solid at the wall points, from the last tangent."""
        if len(self.wall_points) and self.solid_diagonal is not None:
            self.wall_multiplier = penalty * float(np.mean(self.solid_diagonal))
        return self.wall_multiplier


class OrderedFactors:
    """Factors of ``K[order][:, order]`` (SuperLU's or QDLDL's), solving ``K x = b``."""

    def __init__(self, lu, order):
        self.lu, self.order = lu, order

    def solve(self, b):
        x = np.empty_like(b)
        x[self.order] = self.lu.solve(b[self.order])
        return x


def surface_edges(cells, points, on_surface):
    """The quadratic edges (corner, midside, corner) of ``cells`` whose three nodes
    are all ``on_surface``, each run outwards in r (so that ``(dr, -dz)`` is the
    outward normal of the top surface).

    Examples
    --------
    >>> import felupe as fem
    >>> mesh = fem.Rectangle(n=3).add_midpoints_edges()   # (z, r) in [0, 1]^2
    >>> edges = surface_edges(mesh.cells, mesh.points, mesh.points[:, 0] == 1.0)
    >>> mesh.points[edges][:, :, 1].tolist()
    [[0.0, 0.25, 0.5], [0.5, 0.75, 1.0]]
    """
    cells = np.asarray(cells)
    out = []
    for i in range(4):
        j = (i + 1) % 4
        edge = cells[:, [i, 4 + i, j]]
        # FElupe numbers the midside node of corner edge (i, i+1) as 4 + i
        if not np.allclose(points[cells[:, 4 + i]], 0.5 * (points[cells[:, i]] + points[cells[:, j]])):
            raise ValueError("unexpected node numbering of the quadratic cells")
        out.append(edge[np.all(on_surface[edge], axis=1)])
    edges = np.concatenate(out)
    flip = points[edges[:, 0], 1] > points[edges[:, 2], 1]
    edges[flip] = edges[flip][:, ::-1]
    return edges[np.argsort(points[edges[:, 0], 1])]
