"""An Abaqus/CalculiX input deck of the suction-test model, and a CalculiX run of it.

The deck is an independent check of this model (and a start for a user's own FE
code): the same mesh, materials, boundary conditions and follower suction,
written as plain Abaqus keywords that CalculiX (``ccx``) also reads.

Coordinates: FElupe's axisymmetric points are ``(z, r)`` (column 0 the axis);
Abaqus's axisymmetric elements take ``x = r``, ``y = z``. Swapping the columns
mirrors the cells, so the element node order is reversed (corners 1, 4, 3, 2 and
the midside nodes with them) to keep the Jacobian positive.

The load history is one ``*STEP`` per interval between output pressures, each of
time period equal to its pressure increment in mbar: the total time of the
analysis *is* the suction pressure in mbar, so every increment's output of the
apex deflection (node set ``APEX``, ``U2``) is a point of M(p), and every output
pressure ends a step (it is hit exactly). Each step ramps the pressure linearly
from the previous step's value (the default amplitude of a static step).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ._curve import ParameterError
from ._fast import surface_edges

__all__ = ["inp_deck", "write_inp", "run_calculix", "read_dat", "CalculixError"]

MBAR_TO_MPA = 1e-4
#: stress units of the deck, per MPa
STRESS_UNITS = {"Pa": 1e6, "kPa": 1e3, "MPa": 1.0}
#: FElupe/VTK quad8 (corners 0-3, midside 4 + i on corner edge i, i + 1), mirrored
#: by the swap (z, r) -> (x = r, y = z): corners 0, 3, 2, 1 and their midsides
ABAQUS_ORDER = np.array([0, 3, 2, 1, 7, 6, 5, 4])
#: Abaqus's faces of a quadrilateral: face k runs from corner k - 1 to corner k
#: (k = 1..4), in the element's own (Abaqus) node order
_FACES = ((0, 1), (1, 2), (2, 3), (3, 0))
#: FElupe's DOF columns (z, r) -> Abaqus DOFs (2, 1)
_DOF = (2, 1)


class CalculixError(RuntimeError):
    """CalculiX is missing, failed, or wrote no usable result."""


def _f(x):
    """A float as Abaqus and CalculiX read it: 14 significant digits, at most 20
    characters (CalculiX's field width)."""
    return format(float(x), ".14g")


def _lines(ids, per_line=16):
    ids = [str(int(i)) for i in ids]
    return [", ".join(ids[k:k + per_line]) for k in range(0, len(ids), per_line)]


def _refuse(model):
    s = model.settings
    if s.formulation != "displacement":
        raise ParameterError(
            "inp_deck exports the displacement formulation only (CAX8R/CAX8 with a "
            f"volumetric penalty), not formulation {s.formulation!r}")
    if s.edge_radius > 0:
        raise ParameterError(
            "inp_deck cannot export a rounded probe edge (edge_radius > 0): its "
            "sliding contact has no plain Abaqus counterpart here")
    if model.skin.has_prestretch:
        raise ParameterError(
            "inp_deck cannot export a pre-stretched skin (the pre-deformation F0 of "
            "each layer has no plain Abaqus keyword): use prestretch 1")
    if s.element != "quad8":
        raise ParameterError(
            f"inp_deck exports quad8 cells (CAX8R/CAX8), not {s.element!r}: "
            "Abaqus has no 9-node axisymmetric quadrilateral")
    unknown = set(model.boundaries) - {"axis", "glued", "bottom"}
    if unknown:
        raise ParameterError(f"inp_deck cannot export the boundary condition(s) {sorted(unknown)}")


def _check_orientation(points, cells_abq):
    """Every element's corners run anticlockwise in (x = r, y = z): a positive
    area (a cell collapsed onto the aperture edge is a triangle, still positive)."""
    x, y = points[cells_abq[:, :4], 1], points[cells_abq[:, :4], 0]
    area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    if np.any(area <= 0):
        raise RuntimeError(f"{int(np.sum(area <= 0))} element(s) would be inside out")


def _material_sets(model):
    """Element sets, one per layer and distinct (x1, x2, bulk) of its cells:
    ``[(name, layer_name, cells, (x1, x2, bulk)), ...]``, top layer first."""
    umat = model.solid.umat
    ncells = len(model.mesh.cells)
    values = np.stack([np.broadcast_to(np.asarray(v, float), (ncells,))
                       for v in (umat.x1, umat.x2, umat.bulk)], axis=1)
    layer = np.asarray(model.layer)
    names = list(model.layer_names)
    out = []
    for k, layer_name in enumerate(names):
        cells = np.flatnonzero(layer == k)
        distinct, which = np.unique(values[cells], axis=0, return_inverse=True)
        for j, v in enumerate(distinct):
            name = layer_name.upper() if len(distinct) == 1 else f"{layer_name.upper()}_{j + 1}"
            out.append((name, layer_name, cells[which.ravel() == j], tuple(float(x) for x in v)))
    if sum(len(c) for _, _, c, _ in out) != ncells:
        raise ParameterError("inp_deck: every cell must belong to one layer")
    return out


def _material_lines(name, x1, x2, bulk, scale, unit):
    d1 = 2.0 / (bulk * scale)
    head = [f"*MATERIAL, NAME={name}",
            f"** X1 = {x1:.6g} MPa, X2 = {x2:.6g} MPa, K = {bulk:.6g} MPa; in {unit}:"]
    if x2 == 0:
        return head + ["** W = C10 (I1bar - 3) + 1/D1 (J - 1)^2, C10 = X1, D1 = 2/K",
                       "*HYPERELASTIC, NEO HOOKE",
                       f"{_f(x1 * scale)}, {_f(d1)}"]
    return head + ["** W = C10 (I1bar - 3) + C20 (I1bar - 3)^2 + 1/D1 (J - 1)^2, "
                   "C10 = X1, C20 = X2, D1 = 2/K",
                   "** D2 = 1e30: no (J - 1)^4 term (CalculiX divides by D2: 0 is not 'none')",
                   "*HYPERELASTIC, REDUCED POLYNOMIAL, N=2",
                   f"{_f(x1 * scale)}, {_f(x2 * scale)}, {_f(d1)}, 1e+30"]


def _suction_faces(model, cells_abq, used):
    """The loaded faces: ``{face label: [element ids]}`` of the surface inside the
    aperture, from the same edges as the model's suction (zero-length edges of
    collapsed cells dropped)."""
    z, r = model.mesh.points.T
    a = model.parameters["probe_mm"] / 2
    tol = 1e-9 * (a + model.skin.depth)
    inside = np.isclose(z, 0, atol=tol) & (r <= a + tol) & used
    edges = surface_edges(model.mesh.cells, model.mesh.points, inside)
    edges = edges[np.abs(r[edges[:, 2]] - r[edges[:, 0]]) > tol]
    where = {}
    for e, cell in enumerate(cells_abq):
        for k, (i, j) in enumerate(_FACES):
            where.setdefault(frozenset((cell[i], cell[4 + k], cell[j])), []).append((e, k))
    faces = {}
    for edge in edges:
        found = where.get(frozenset(edge.tolist()), [])
        if len(found) != 1:
            raise RuntimeError(f"suction edge {edge.tolist()} lies on {len(found)} cells")
        e, k = found[0]
        faces.setdefault(k + 1, []).append(e + 1)
    return faces


def _header(model, p, stress_unit, scale, element, cells, used):
    """The deck's heading and comment lines (skin, units, mesh, what it omits), and
    the ``*NODE`` keyword that follows them."""
    import skinsuction

    s = model.settings
    force = {"Pa": "uN", "kPa": "mN", "MPa": "N"}[stress_unit]
    probe = model.parameters["probe_mm"]
    a = probe / 2
    skin = model.skin
    collapsed = sum(len(set(c)) < 8 for c in cells.tolist())
    version = skinsuction.__version__
    out = ["*HEADING",
           f"Skin suction test: {probe:g} mm probe, {len(skin.layers)} layer(s), "
           f"skinsuction {version}",
           f"** Written by skinsuction {version} (skinsuction.model.inp_deck): the model",
           "** skinsuction.model.SuctionTest solves, for any FE code that reads Abaqus input.",
           "** Axisymmetric suction (Cutometer) test. The skin is glued to the probe's face",
           f"** outside the aperture (z = 0, r >= a = {a:g} mm) and sucked into it by a",
           "** follower pressure on its free surface inside (z = 0, r < a).",
           f"** Units: mm, {stress_unit} (forces in {force}); 1 mbar = "
           f"{_f(MBAR_TO_MPA * scale)} {stress_unit}.",
           "** Coordinates: x = r (radius), y = z (axial, up; skin surface y = 0, bottom "
           f"y = {-skin.depth:g}).",
           "** Output: U2 of node set APEX (the apex deflection M, mm) in the .dat file.",
           "** Skin, top layer first:"]
    for layer in skin.layers:
        out.append(f"**   {layer.name}: thickness {layer.thickness:g} mm, X1 = {layer.X1:g} "
                   f"MPa, X2 = {layer.X2:g} MPa")
    out += [f"** Bottom: {skin.bottom} (fixed: U1 = U2 = 0; axial: U2 = 0; free: none).",
            "** W = X1 (I1bar - 3) + X2 (I1bar - 3)^2 + K/2 (J - 1)^2, K = 4 X1 (1 + nu) / "
            f"(3 (1 - 2 nu)), nu = {model.parameters['poisson']:g}.",
            f"** Probe: aperture diameter {probe:g} mm. Pressures (mbar), each the end of "
            f"a step: {' '.join(f'{v:g}' for v in p)}",
            "** The total time of the analysis is the suction pressure in mbar.",
            f"** Mesh: {s.corner} corner, refinement {s.refinement:g}, {len(cells)} {element}"
            f" elements ({collapsed} collapsed onto the aperture edge), "
            f"{int(used.sum())} nodes.",
            "** OMITTED: the frictionless rigid probe wall at r = a (skinsuction's mesh",
            "**   setting probe_wall, a penalty contact that acts only where the skin",
            "**   bulges past r = a): this deck is the model with probe_wall False.",
            "*NODE, NSET=NALL"]
    return out


def _boundary_sets(model, used, out):
    """Append the node sets of the fixed DOFs (axis, glued face, bottom) to ``out``;
    returns ``(set name, Abaqus DOF)`` pairs for ``*BOUNDARY``."""
    fixed = []
    for key in ("axis", "glued", "bottom"):
        if key not in model.boundaries:
            continue
        boundary = model.boundaries[key]
        if np.any(np.asarray(boundary.value) != 0):
            raise ParameterError(f"inp_deck: boundary {key!r} prescribes a non-zero value")
        mask = np.asarray(boundary.mask, dtype=bool) & used[:, None]
        for col in (1, 0):  # Abaqus DOF 1 (r), then 2 (z)
            nodes = np.flatnonzero(mask[:, col])
            if len(nodes):
                name = f"{key.upper()}_U{_DOF[col]}"
                out.append(f"*NSET, NSET={name}")
                out += _lines(nodes + 1)
                fixed.append((name, _DOF[col]))

    return fixed


def _steps(p, faces, max_increment_mbar, scale):
    """One ``*STEP`` per output pressure: the suction ramped over it as a follower
    ``*DLOAD`` on the surface faces, the apex printed at every increment."""
    out = []
    for p0, p1 in zip(p[:-1], p[1:]):
        dp = p1 - p0
        inc = min(dp, float(max_increment_mbar))
        out += [f"** {p0:g} -> {p1:g} mbar, ramped over a step time of {dp:g}",
                "*STEP, NLGEOM=YES, INC=10000",
                "*STATIC",
                f"{_f(inc)}, {_f(dp)}, {_f(dp * 1e-6)}, {_f(inc)}",
                "** equilibrium to 1e-7 of the mean nodal force (default 5e-3)",
                "*CONTROLS, PARAMETERS=FIELD",
                "1e-7, 1e-6",
                "** suction: a negative (outward) pressure, following the surface",
                "*DLOAD"]
        out += [f"SUCTION_P{k}, P{k}, {_f(-p1 * MBAR_TO_MPA * scale)}" for k in sorted(faces)]
        out += ["*NODE PRINT, NSET=APEX", "U", "*END STEP"]
    return out


def inp_deck(model, pressures_mbar=(0.0, 100.0), max_increment_mbar=10.0,
             stress_unit="Pa") -> str:
    """An Abaqus/CalculiX input deck of a built suction-test model.

    Parameters
    ----------
    model : SuctionTest
        The model (displacement formulation, quad8 cells, sharp probe edge, no
        pre-stretch; any number of layers, any bottom condition). Its probe wall
        contact, if on, is left out (the deck says so): compare the deck with the
        model built with ``mesh={"probe_wall": False}``.
    pressures_mbar : array_like
        Output pressures in mbar, from 0, ascending: each ends a load step.
    max_increment_mbar : float
        Largest load increment (mbar) the solver may take; it cuts back below it
        where an increment fails to converge.
    stress_unit : {"Pa", "kPa", "MPa"}
        Unit of the moduli and the pressure; lengths are in mm (so forces are in
        uN, mN or N). Pa by default: CalculiX (and Abaqus) start a step's time
        average of the forces at 0.01 when there is none yet, and against it the
        nodal forces of this soft problem in N (1e-5 and less) pass the residual
        test after two iterations, unconverged (0.4 % off on the 6 mm reference
        skin at 25 mbar in one increment, 4 % on a soft skin). In uN the mean
        force is 0.1 and more, and the test is a real one (docs/calculix.md).

    Returns
    -------
    str
        The deck: ``CAX8R`` elements (``CAX8`` for full integration), one element
        set and ``*MATERIAL`` per layer (neo-Hookean, or the reduced polynomial of
        order 2 where X2 > 0; a layer whose cells differ gets a set per distinct
        material), the boundary conditions as node sets, the suction as a follower
        ``*DLOAD`` on the free surface inside the aperture, and the apex deflection
        (node set ``APEX``, ``U2``) printed to the ``.dat`` file at every increment.

    Raises
    ------
    ParameterError
        For what the deck cannot carry (the mixed formulation, a pre-stretch, a
        rounded probe edge, quad9 cells), for pressures that do not start at 0 and
        increase, or an unknown unit.

    Examples
    --------
    >>> from skinsuction.model import Skin, SuctionTest
    >>> model = SuctionTest(Skin.two_layer(0.08, 4.1e-4), 2.0,
    ...                     {"refinement": 0.5, "probe_wall": False})
    >>> deck = inp_deck(model, [0, 50, 100])
    >>> [line for line in deck.splitlines() if line.startswith("*ELEMENT")]
    ['*ELEMENT, TYPE=CAX8R, ELSET=DERMIS', '*ELEMENT, TYPE=CAX8R, ELSET=HYPODERMIS']
    >>> deck.count("*STEP"), deck.count("*MATERIAL"), deck.count("*HYPERELASTIC, NEO HOOKE")
    (2, 2, 2)
    """
    _refuse(model)
    p = np.asarray(pressures_mbar, dtype=float).ravel()
    if len(p) < 2 or p[0] != 0 or np.any(np.diff(p) <= 0) or not np.all(np.isfinite(p)):
        raise ParameterError(
            f"pressures must start at 0 and increase strictly, not {p.tolist()}")
    if not max_increment_mbar > 0:
        raise ParameterError(f"max_increment_mbar must be positive, not {max_increment_mbar!r}")
    if stress_unit not in STRESS_UNITS:
        raise ParameterError(
            f"stress_unit must be one of {sorted(STRESS_UNITS)}, not {stress_unit!r}")
    scale = STRESS_UNITS[stress_unit]
    s = model.settings
    cells = np.asarray(model.mesh.cells)
    points = np.asarray(model.mesh.points, dtype=float)
    used = np.zeros(len(points), dtype=bool)
    used[cells.ravel()] = True  # the probe's reference point is in no cell
    cells_abq = cells[:, ABAQUS_ORDER]
    _check_orientation(points, cells_abq)
    element = "CAX8R" if s.quadrature == "reduced" else "CAX8"

    out = _header(model, p, stress_unit, scale, element, cells, used)
    for n in np.flatnonzero(used):
        out.append(f"{n + 1}, {_f(points[n, 1])}, {_f(points[n, 0])}")

    sets = _material_sets(model)
    for name, _, ids, _ in sets:
        out.append(f"*ELEMENT, TYPE={element}, ELSET={name}")
        for e in ids:
            out.append(f"{e + 1}, " + ", ".join(str(n + 1) for n in cells_abq[e]))
    for name, _, _, _ in sets:
        out.append(f"*SOLID SECTION, ELSET={name}, MATERIAL={name}")
    for name, _, _, (x1, x2, bulk) in sets:
        out += _material_lines(name, x1, x2, bulk, scale, stress_unit)

    out += ["*NSET, NSET=APEX", f"{model.apex + 1}"]
    fixed = _boundary_sets(model, used, out)
    faces = _suction_faces(model, cells_abq, used)
    for k, ids in sorted(faces.items()):
        out.append(f"*ELSET, ELSET=SUCTION_P{k}")
        out += _lines(ids)
    out.append("*BOUNDARY")
    out += [f"{name}, {dof}, {dof}" for name, dof in fixed]

    out += _steps(p, sorted(faces), max_increment_mbar, scale)
    return "\n".join(out) + "\n"


def write_inp(model, path, pressures_mbar=(0.0, 100.0), max_increment_mbar=10.0,
              stress_unit="Pa") -> Path:
    """Write :func:`inp_deck` to ``path`` atomically (a temporary file, renamed).

    Parameters
    ----------
    model, pressures_mbar, max_increment_mbar, stress_unit
        As for :func:`inp_deck`.
    path : path
        The ``.inp`` file to write (its directory must exist).

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    text = inp_deck(model, pressures_mbar, max_increment_mbar, stress_unit)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="ascii") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


_BLOCK = re.compile(r"displacements \(vx,vy,vz\) for set APEX and time\s+(\S+)")


def read_dat(path):
    """Apex deflection (U2 of node set ``APEX``) at every increment of a CalculiX
    ``.dat`` file: ``(time, U2)`` arrays; the time is the pressure in mbar."""
    lines = Path(path).read_text(errors="replace").splitlines()
    times, values = [], []
    for i, line in enumerate(lines):
        m = _BLOCK.search(line)
        if not m:
            continue
        for row in lines[i + 1:]:
            if row.strip():
                fields = row.split()
                times.append(float(m.group(1)))
                values.append(float(fields[2]))
                break
    return np.array(times), np.array(values)


def run_calculix(deck, workdir, pressures_mbar=None, ccx=None, jobname="suction",
                 timeout=None, threads=1):
    """Run a deck of :func:`inp_deck` in CalculiX and read M(p) back.

    Parameters
    ----------
    deck : str
        The deck's text.
    workdir : path
        Directory for the job's files (``<jobname>.inp``, ``.dat``, ``.sta``,
        ``.frd``, and ``<jobname>.log``: what ccx printed); made if absent.
    pressures_mbar : array_like, optional
        The pressures to return, each one the analysis reached (the deck's
        output pressures are); default: every increment.
    ccx : str, optional
        The CalculiX executable (default: ``ccx`` on PATH).
    jobname : str
        Name of the job's files.
    timeout : float, optional
        Seconds before the run is given up.
    threads : int
        Threads ccx may use.

    Returns
    -------
    pressure_mbar, deflection_mm : ndarray
        M(p), from (0, 0) unless ``pressures_mbar`` says otherwise.

    Raises
    ------
    CalculixError
        If ``ccx`` is not found, stops with an error (no convergence included) or
        its ``.dat`` file lacks a requested pressure; the message names the files.
    """
    exe = shutil.which(ccx or "ccx")
    if exe is None:
        raise CalculixError(
            f"CalculiX ({ccx or 'ccx'}) is not on PATH: install it (Debian, Ubuntu: "
            "apt-get install calculix-ccx) or pass its path as ccx")
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    job = workdir / jobname
    Path(f"{job}.inp").write_text(deck, encoding="ascii")
    for suffix in (".dat", ".sta"):  # a failed run must not leave an older result
        Path(f"{job}{suffix}").unlink(missing_ok=True)
    files = f"see {job}.sta, {job}.dat and {job}.log"
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_STIFFNESS=str(threads),
               CCX_NPROC_EQUATION_SOLVER=str(threads))
    try:
        done = subprocess.run([exe, "-i", jobname], cwd=workdir, env=env, timeout=timeout,
                              capture_output=True, text=True, errors="replace")
        log = done.stdout + done.stderr
    except subprocess.TimeoutExpired as err:
        log = (err.stdout or b"").decode(errors="replace") if isinstance(err.stdout, bytes) \
            else (err.stdout or "")
        Path(f"{job}.log").write_text(log)
        raise CalculixError(f"CalculiX ran out of {timeout:g} s on {job}.inp ({files})") from None
    Path(f"{job}.log").write_text(log)
    dat = Path(f"{job}.dat")
    t, u = read_dat(dat) if dat.exists() else (np.zeros(0), np.zeros(0))
    errors = [line.strip() for line in log.splitlines() if "*ERROR" in line]
    if done.returncode != 0 or errors:
        reached = f"; last output at {t[-1]:g} mbar" if len(t) else ""
        raise CalculixError(
            f"CalculiX stopped on {job}.inp (exit {done.returncode}): "
            f"{' '.join(errors[:2]) or 'no message'}{reached} ({files})")
    t, u = np.concatenate([[0.0], t]), np.concatenate([[0.0], u])
    if pressures_mbar is None:
        return t, u
    p = np.asarray(pressures_mbar, dtype=float)
    out = np.empty(p.shape)
    for i, target in enumerate(p):
        hit = np.flatnonzero(np.isclose(t, target, rtol=1e-9, atol=1e-9))
        if not len(hit):
            raise CalculixError(
                f"CalculiX wrote no output at {target:g} mbar (last at {t[-1]:g} mbar; "
                f"{files})")
        out[i] = u[hit[-1]]
    return p, out
