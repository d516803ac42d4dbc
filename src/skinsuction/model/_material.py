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

    Parameters
    ----------
    x1, x2, bulk : array_like
        Per-cell parameters, shape ``(ncells,)`` (or scalars), in MPa.

    Examples
    --------
    >>> import numpy as np
    >>> umat = SkinLayers(x1=[0.1, 0.2], x2=0.0, bulk=bulk_modulus([0.1, 0.2]))
    >>> F = np.eye(3)[:, :, None, None] * np.ones((1, 1, 4, 2))
    >>> float(abs(umat.gradient([F, None])[0]).max()) < 1e-14
    True
    """

    def __init__(self, x1, x2, bulk):
        self.x1 = np.asarray(x1, dtype=float)
        self.x2 = np.broadcast_to(np.asarray(x2, dtype=float), self.x1.shape)
        self.bulk = np.broadcast_to(np.asarray(bulk, dtype=float), self.x1.shape)
        self.x = [np.eye(3), np.zeros(0)]

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
        F, statevars = x[0], x[-1]
        J, iFT, I1, G = self._kinematics(F)
        W1 = self.x1 + 2 * self.x2 * (G * I1 - 3)
        dI1bar = G * (2 * F - 2 / 3 * I1 * iFT)
        P = W1 * dI1bar + self.bulk * (J - 1) * J * iFT
        return [P, statevars]

    def hessian(self, x):
        F = x[0]
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
        return [A]
