"""Quasi-incompressible isotropic hyperelastic skin layers with per-cell parameters."""

import numpy as np


def bulk_modulus(x1, poisson=0.49):
    """Penalty bulk modulus equivalent to a Poisson ratio in the small-strain limit.

    The initial shear modulus of ``W = X1 (I1 - 3) + ...`` is ``mu = 2 X1``, so
    ``K = 2 mu (1 + nu) / (3 (1 - 2 nu))``.

    Examples
    --------
    >>> round(float(bulk_modulus(0.5, poisson=0.49)), 6)
    49.666667
    """
    mu = 2 * np.asarray(x1, dtype=float)
    return 2 * mu * (1 + poisson) / (3 * (1 - 2 * poisson))


class SkinLayers:
    r"""Isochoric second-order polynomial in the first invariant plus a volumetric
    penalty, with one parameter set per cell (dermis and hypodermis in one body).

    ..  math::

        W = X_1 (\bar I_1 - 3) + X_2 (\bar I_1 - 3)^2 + \frac{K}{2} (J - 1)^2,
        \qquad \bar I_1 = J^{-2/3} \operatorname{tr}(\boldsymbol C)

    ``X2 = 0`` is the paper's neo-Hookean eq. 1 and FElupe's ``NeoHooke(mu=2 X1,
    bulk=K)``; ``X2 > 0`` is the paper's eq. 9. FElupe's own ``NeoHooke`` cannot take
    per-cell arrays beyond 2048 cells (it evaluates in chunks), hence this class, which
    follows FElupe's material protocol (``gradient``/``hessian`` of ``[F, statevars]``).

    An optional diagonal pre-deformation ``F0`` (per cell) makes the mesh's
    configuration a pre-stretched one: the energy per unit of that configuration is
    ``W(F F0) / det(F0)``, so the body is pre-stressed at ``F = 1``.

    Parameters
    ----------
    x1, x2, bulk : array_like
        Per-cell parameters, shape ``(ncells,)`` (or scalars), in MPa.
    prestretch : array_like, optional
        Diagonal of ``F0`` per cell, shape ``(3, ncells)`` (or ``(3,)``), in FElupe's
        axisymmetric order (axial, radial, hoop). Default: no pre-stretch.

    Examples
    --------
    >>> import numpy as np
    >>> umat = SkinLayers(x1=[0.1, 0.2], x2=0.0, bulk=bulk_modulus([0.1, 0.2]))
    >>> F = np.eye(3)[:, :, None, None] * np.ones((1, 1, 4, 2))
    >>> float(abs(umat.gradient([F, None])[0]).max()) < 1e-14
    True
    """

    def __init__(self, x1, x2, bulk, prestretch=None):
        self.x1 = np.asarray(x1, dtype=float)
        self.x2 = np.broadcast_to(np.asarray(x2, dtype=float), self.x1.shape)
        self.bulk = np.broadcast_to(np.asarray(bulk, dtype=float), self.x1.shape)
        self.x = [np.eye(3), np.zeros(0)]
        self.F0 = None
        if prestretch is not None:
            F0 = np.asarray(prestretch, dtype=float).reshape(3, -1)
            # (F F0)_iJ = F_iJ F0_J: a column scaling, broadcast over Gauss points
            self.F0 = F0[None, :, None, :]
            self.J0 = np.prod(F0, axis=0)

    def _pre(self, F):
        return F if self.F0 is None else F * self.F0

    @staticmethod
    def _kinematics(F):
        # cofactor by cross products of the columns: faster than a batched
        # np.linalg.inv of many 3x3 matrices, and J comes with it
        cof = np.stack(
            [np.cross(F[:, 1], F[:, 2], axis=0),
             np.cross(F[:, 2], F[:, 0], axis=0),
             np.cross(F[:, 0], F[:, 1], axis=0)],
            axis=1,
        )
        J = np.einsum("iqc,iqc->qc", F[:, 0], cof[:, 0])
        iFT = cof / J
        I1 = np.einsum("iJqc,iJqc->qc", F, F)
        G = J ** (-2 / 3)
        return J, iFT, I1, G

    def gradient(self, x):
        F, statevars = self._pre(x[0]), x[-1]
        P = self._gradient(F)
        if self.F0 is not None:
            P = P * self.F0 / self.J0
        return [P, statevars]

    def _gradient(self, F):
        J, iFT, I1, G = self._kinematics(F)
        W1 = self.x1 + 2 * self.x2 * (G * I1 - 3)
        dI1bar = G * (2 * F - 2 / 3 * I1 * iFT)
        return W1 * dI1bar + self.bulk * (J - 1) * J * iFT

    def hessian(self, x):
        A = self._hessian(self._pre(x[0]))
        if self.F0 is not None:
            A = A * (self.F0[:, :, None, None] * self.F0[None, None] / self.J0)
        return [A]

    def _hessian(self, F):
        J, iFT, I1, G = self._kinematics(F)
        W1 = self.x1 + 2 * self.x2 * (G * I1 - 3)
        dI1bar = G * (2 * F - 2 / 3 * I1 * iFT)

        def outer(A, B):
            return A[:, :, None, None] * B[None, None, :, :]

        # the terms of W1 d2(I1bar)/dFdF and of the penalty, grouped by tensor
        # product so that few (3,3,3,3,q,c) temporaries are made
        A = outer(iFT, (W1 * G * 4 / 9 * I1 + self.bulk * (2 * J - 1) * J) * iFT)
        A += np.einsum("iLqc,kJqc->iJkLqc", iFT, (W1 * G * 2 / 3 * I1 - self.bulk * (J - 1) * J) * iFT)
        B = outer(F, -4 / 3 * W1 * G * iFT)
        A += B
        A += B.transpose(2, 3, 0, 1, 4, 5)
        A += outer(dI1bar, 2 * self.x2 * dI1bar)
        diagonal = 2 * W1 * G
        for i in range(3):
            for j in range(3):
                A[i, j, i, j] += diagonal
        return A


def thickness_stretch(prestretch, x1, x2=0.0, poisson=0.49):
    """Stretch through the thickness that keeps the skin surface traction-free under
    an equibiaxial in-plane pre-stretch (plane stress, with the volumetric penalty).

    Examples
    --------
    >>> round(float(thickness_stretch(1.0, 0.1)), 12)
    1.0
    >>> 0.90 < float(thickness_stretch(1.05, 0.1)) < 1 / 1.05
    True
    """
    from scipy.optimize import brentq

    if prestretch == 1:
        return 1.0
    umat = SkinLayers(x1=[x1], x2=[x2], bulk=bulk_modulus([x1], poisson))

    def axial_stress(stretch):
        F = np.diag([stretch, prestretch, prestretch])[:, :, None, None]
        return float(umat.gradient([F, None])[0][0, 0, 0, 0])

    return brentq(axial_stress, 0.05, 1.5, xtol=1e-14)


def prestress(prestretch, x1, x2=0.0, poisson=0.49):
    """In-plane Cauchy stress (MPa) of the pre-stretched, traction-free skin.

    Examples
    --------
    >>> float(prestress(1.0, 0.1))
    0.0
    """
    stretch = thickness_stretch(prestretch, x1, x2, poisson)
    if stretch == 1.0:
        return 0.0
    F = np.diag([stretch, prestretch, prestretch])[:, :, None, None]
    umat = SkinLayers(x1=[x1], x2=[x2], bulk=bulk_modulus([x1], poisson))
    P = umat.gradient([F, None])[0]
    return float(P[1, 1, 0, 0] * prestretch / (stretch * prestretch**2))
