"""The simulated space Omega_s: FE curves computed once, interpolated off their nodes.

Two layouts of one abstraction.  The **grid** of the paper (section 2.3):
one FE curve per (X1d, X1h) node, cubic Lagrange in X1d, X1h and p
(:class:`SimulatedSpace`, :class:`GriddedSpace`).  The **scale-free** space:
by the scaling law M(s X1d, s X1h, s X2d, s p) = M(X1d, X1h, X2d, p) one FE
*ray* per (X1h/X1d, cause coordinate), loaded to p/X1d = ``load_max``, covers
every X1d and every pressure protocol (:class:`RaySpace`,
:class:`RayInterpolant`, :class:`NeoHookeanSlice`).  Both are read by
:func:`load_space` as one :class:`ProbeSpace` per probe, which is all that
:mod:`skinsuction.identify` and :mod:`skinsuction.diagnose` ask of a space:
deflections at (candidates, pressures).

The grid axes and the ray ids keep the paper's two-layer keywords (``x1d``,
``t_d``, ...: they are data, :data:`AXES`); where a function takes a skin's
values it names them by parameter path of :class:`skinsuction.model.Skin`
(``"dermis.thickness"``, ``"dermis.X2"``; :data:`AXIS_PATHS`).

Modules:

* ``_storage``: point ids, curve files, Parquet with provenance;
* ``_solve``: FE solves with fallback meshes;
* ``_grid``: the grid layout's database (:class:`SimulatedSpace`);
* ``_lagrange``: local cubic Lagrange weights on one axis;
* ``_interpolate``: a grid of one probe (:class:`GriddedSpace`) interpolated,
  with its NaN policy;
* ``_causes``: the causes and their ray coordinates;
* ``_coordinates``: a skin's coordinates in the space (ratio, load, t/a, cause
  coordinate) and back (:class:`SpaceCoordinates`);
* ``_rays``: which rays a scale-free space has (ids, :class:`RaySpec`, FE jobs);
* ``_ray_space``: the rays stored and read back (:class:`RaySpace`);
* ``_ray_solve``, ``_ray_interpolate``: the rays solved and interpolated;
* ``_neo_hookean_slice``: the neo-Hookean rays of one probe, tabulated per protocol
  for the identification;
* ``_pairs``, ``_pair_interpolate``: spaces of two causes at once, and read off
  their nodes;
* ``_on_demand``: rays at a measurement's own probe and layers, solved on
  demand and cached (:class:`OnDemandRays`);
* ``_deferred``: rays read first, solved only where a fit shows they matter
  (:class:`DeferredRays`);
* ``_geometry_space``: the neo-Hookean rays over the subject's geometry, read
  by interpolation (:class:`GeometrySpace`); rays on demand read it first;
* ``_geometry``: the spaces of one measurement (:func:`spaces_at`);
* ``_open``: either layout, per probe (:func:`load_space`);
* ``_shipped``: the default space (the workflow's build in the working
  directory, else the one shipped with the package) and shipping a build;
* ``_shipped_check``: a fresh build compared with the shipped space;
* ``_shipped_pairs``: the pair spaces that go with a space, and shipping them.

Examples
--------
>>> import numpy as np
>>> from skinsuction.space import GriddedSpace, point_id
>>> p = np.arange(0.0, 101.0, 50.0)
>>> s = GriddedSpace([0.01, 0.02], [1e-4, 2e-4], p, np.broadcast_to(p / 1e3, (2, 2, 3)), 6)
>>> s.interpolant_at([75.0])([[0.015, 1.5e-4]]).round(6).tolist()
[[0.075]]
>>> point_id({"probe_mm": 6, "x1d": 0.08, "x1h": 0.00041})
'p6_fixed_x1d0.08_x1h0.00041_x2d0_x2h0_td1_th1'
"""

from skinsuction._files import atomic_output, write_table
from skinsuction.measured import DEFAULT_LAYERS_MM, Geometry

from ._causes import (
    BASELINE,
    DEFAULT_CAUSES,
    NONE,
    SCALES,
    Cause,
    default_registry,
    registry_from_config,
)
from ._geometry import (
    FIT_REACH,
    THICKNESS_RESOLUTION_MM,
    GeometryOutsideSpace,
    ThicknessNuisance,
    fit_reach_mm,
    spaces_at,
    window_nodes,
)
from ._grid import (
    SLICE_PATHS,
    SimulatedSpace,
    assemble_space,
    convergence_summary,
    expand_axis,
    grid_points,
    read_space,
)
from ._interpolate import GriddedSpace, SpaceInterpolant, evaluate, interpolate_pressure
from ._lagrange import LagrangeAxis
from ._load_axis import LoadAxis
from ._coordinates import SpaceCoordinates, load, reference_pressure, similar_length
from ._on_demand import LAYER_PATHS, OnDemandRays, default_cache_dir, layer_thicknesses
from ._deferred import DeferredRays
from ._open import GEOMETRIES_KEPT, LoadedSpace, ProbeSpace, load_space
from ._neo_hookean_slice import NeoHookeanSlice, TabulatedInterpolant
from ._ray_interpolate import RayInterpolant, read_at_once
from ._pair_interpolate import PairRayInterpolant, interpolant
from ._pairs import (
    PAIRS_FOLDER,
    CausePair,
    PairRaySpace,
    assemble_pair_space,
    pair_bundles,
    pair_from_config,
    pair_rays,
    pairs_from_config,
    read_pair_space,
    read_pair_spaces,
    space_causes,
)
from ._geometry_files import (default_geometry_file, geometry_file_for, ship_geometry_space,
                              unpack_geometry_space)
from ._geometry_space import (
    GEOMETRY_FOLDER,
    GeometryGrid,
    GeometrySpace,
    assemble_geometry_space,
    cause_coordinates,
    cause_geometry_space,
    read_geometry_space,
    same_rays,
)
from ._ray_solve import build_ray_spaces, compute_bundle, compute_ray
from ._ray_space import (
    RaySpace,
    SpaceFileError,
    SpaceMissingError,
    assemble_ray_space,
    coverage_frontier,
    read_ray_space,
    read_ray_spaces,
)
from ._rays import (
    BUNDLE_ID_PATTERN,
    EXTRA_KEYWORDS,
    RAY_ID_PATTERN,
    RaySpec,
    bundle_id,
    parse_ray_id,
    ray_bundles,
    ray_id,
    rays_of,
)
from ._shipped import (
    PROVENANCE_FILE,
    SHIPPED_SPACE_DIR,
    WORKFLOW_SPACE_DIR,
    SpaceSource,
    default_space_dir,
    resolve_space,
    ship_space,
    shipped_provenance,
    verify_shipped_files,
)
from ._shipped_pairs import pairs_for, ship_pair_spaces
from ._shipped_check import (
    SHIPPED_ATOL_MM,
    SHIPPED_RTOL,
    ShippedSpaceMismatch,
    check_shipped_sample,
    check_shipped_space,
    compare_ray_spaces,
    knife_edge_rays,
    sample_bundles,
    shipped_check_applies,
)
from ._solve import compute_point, compute_points, solve_with_fallbacks, two_layer_skin
from ._storage import (
    AXES,
    AXIS_PATHS,
    BOTTOMS,
    COLUMNS,
    DEFAULTS,
    METADATA_KEY,
    POINT_ID_PATTERN,
    ROW_ID_PATTERN,
    SIGNIFICANT_DIGITS,
    SPEC_KEYS,
    CorruptCurveError,
    curve_frame,
    parse_point_id,
    point_id,
    read_curve,
    read_curves,
    round_sig,
    row_id,
    write_curve,
    write_curves,
)

__all__ = [
    # the abstraction
    "ProbeSpace", "LoadedSpace", "load_space", "GEOMETRIES_KEPT",
    # the default space: the workflow's build here, else the one shipped with the package
    "WORKFLOW_SPACE_DIR", "SHIPPED_SPACE_DIR", "PROVENANCE_FILE", "SpaceSource",
    "default_space_dir", "resolve_space", "shipped_provenance", "verify_shipped_files",
    "shipped_check_applies", "compare_ray_spaces", "knife_edge_rays", "check_shipped_space",
    "check_shipped_sample", "sample_bundles",
    "ShippedSpaceMismatch", "ship_space", "ship_pair_spaces", "SHIPPED_RTOL", "SHIPPED_ATOL_MM",
    # storage
    "AXES", "AXIS_PATHS", "BOTTOMS", "COLUMNS", "DEFAULTS", "METADATA_KEY", "POINT_ID_PATTERN",
    "SIGNIFICANT_DIGITS", "SPEC_KEYS", "CorruptCurveError", "curve_frame", "parse_point_id",
    "point_id", "read_curve", "read_curves", "round_sig", "row_id", "ROW_ID_PATTERN",
    "write_curve", "write_curves",
    "atomic_output", "write_table",
    # FE solves
    "compute_point", "compute_points", "solve_with_fallbacks", "two_layer_skin",
    # the grid layout
    "SimulatedSpace", "SLICE_PATHS", "assemble_space", "convergence_summary", "expand_axis", "grid_points",
    "read_space", "GriddedSpace",
    # interpolation
    "LagrangeAxis", "LoadAxis", "SpaceInterpolant", "evaluate", "interpolate_pressure",
    # the scale-free layout
    "BASELINE", "DEFAULT_CAUSES", "NONE", "SCALES", "Cause", "default_registry",
    "registry_from_config", "BUNDLE_ID_PATTERN", "EXTRA_KEYWORDS", "RAY_ID_PATTERN",
    "PAIRS_FOLDER", "CausePair", "PairRayInterpolant", "PairRaySpace", "assemble_pair_space",
    "interpolant", "pair_bundles", "pair_from_config", "pair_rays", "pairs_for", "pairs_from_config",
    "read_pair_space", "read_pair_spaces", "space_causes",
    "RaySpace", "RaySpec", "SpaceFileError", "SpaceMissingError", "assemble_ray_space",
    "build_ray_spaces", "bundle_id", "compute_bundle", "compute_ray", "coverage_frontier",
    "parse_ray_id", "ray_bundles", "ray_id", "rays_of", "read_ray_space", "read_ray_spaces",
    "NeoHookeanSlice", "RayInterpolant", "TabulatedInterpolant", "read_at_once",
    # every probe and the subject's layers
    "DEFAULT_LAYERS_MM", "Geometry", "GeometryOutsideSpace", "OnDemandRays", "DeferredRays",
    "default_cache_dir", "spaces_at", "fit_reach_mm", "FIT_REACH", "ThicknessNuisance", "window_nodes",
    "GEOMETRY_FOLDER", "GeometryGrid", "GeometrySpace", "assemble_geometry_space",
    "default_geometry_file", "read_geometry_space", "same_rays", "ship_geometry_space",
    "unpack_geometry_space",
    "geometry_file_for", "cause_coordinates", "cause_geometry_space",
    "THICKNESS_RESOLUTION_MM", "LAYER_PATHS", "layer_thicknesses",
    "SpaceCoordinates", "load", "reference_pressure", "similar_length",
]
