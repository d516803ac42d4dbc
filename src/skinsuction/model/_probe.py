"""The rigid probe as a contact surface: the inner wall of the aperture, with a
rounded edge where it meets the glued face."""

import felupe as fem
import numpy as np

from ._curve import ParameterError


class ProbeEdge(fem.mechanics.ContactRigidBase):
    r"""Frictionless penalty contact of skin points with the rigid probe.

    In FElupe's axisymmetric coordinates (z up, r), relative to the centre-point
    ``(0, a + R)`` on the glued face, the probe is the union of the wall
    ``r >= a, z >= R`` and a fillet of radius ``R`` centred at ``(R, a + R)``,
    which joins the wall to the glued face ``z = 0, r >= a + R`` with a continuous
    tangent. Above the fillet centre the gap is the distance to the wall, below
    it the distance to the fillet (the two agree at ``z = R``).

    Parameters
    ----------
    field : felupe.FieldContainer
        The displacement field.
    points : array_like of int
        Skin surface points that may touch the probe.
    centerpoint : int
        A fixed point at ``(0, a + R)``: it places the probe, so ``a`` itself is
        not needed.
    edge_radius : float
        ``R``, the radius of the rounded edge, in mm (positive).
    **kwargs
        Passed on to :class:`felupe.mechanics.ContactRigidBase`.

    Examples
    --------
    A point just inside the fillet is in contact (negative gap); one on the axis
    is not (positive gap).

    >>> import numpy as np, felupe as fem
    >>> mesh = fem.Rectangle(n=3)
    >>> mesh.update(points=np.vstack([mesh.points, [0.0, 1.2]]))
    >>> field = fem.FieldContainer([fem.Field(fem.RegionQuad(mesh), dim=2)])
    >>> edge = ProbeEdge(field, [0, 8], 9, edge_radius=0.2)  # a = 1
    >>> gap, normal, _ = edge._kinematics(np.array([[0.05, -0.05], [0.0, -1.2]]))
    >>> bool(gap[0] < 0), bool(gap[1] > 0)
    (True, True)
    """

    def __init__(self, field, points, centerpoint, edge_radius, **kwargs):
        if not edge_radius > 0:
            raise ParameterError(f"edge_radius must be positive, not {edge_radius!r}")
        self.edge_radius = float(edge_radius)
        super().__init__(field, points, centerpoint, **kwargs)

    def _kinematics(self, dx):
        R = self.edge_radius
        # relative to the fillet centre
        d = dx - np.array([R, 0.0])
        on_wall = d[:, 0] >= 0.0
        distance = np.linalg.norm(d, axis=1)
        distance = np.maximum(distance, np.sqrt(np.finfo(float).eps) * R)
        normal = d / distance[:, None]
        gap = distance - R
        curvature = (np.eye(2) - np.einsum("ai,aj->aij", normal, normal)) / distance[:, None, None]

        # the wall r = a faces the axis: gap a - r, normal -e_r, flat
        gap[on_wall] = -d[on_wall, 1] - R
        normal[on_wall] = [0.0, -1.0]
        curvature[on_wall] = 0.0
        return gap, normal, curvature
