"""The package's layers import one way, and no module imports itself back.

Layers, lowest first (docs/workflow.md#layout): the shared helpers, the model,
its viscoelastic extension, the simulated space, the figures (drawing plain tables), identify, diagnose,
then the studies (paper, cohort, design, and evaluation: the study of the method) and the
command line.  A module may import from its own layer and the layers below, never
from above, so the forward model knows nothing of spaces and neither the paper's
study nor the evaluation of the method is needed to identify or diagnose a curve.  Imports inside functions count: they are arrows too.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = SRC / "skinsuction"

LAYERS = [
    {"errors", "_files", "_threads", "_memory", "_argtypes", "_progress", "provenance", "noise",
     "config", "measured", "jobs", "results"},
    {"model"},
    {"viscoelastic"},
    {"space"},
    {"figures"},
    {"identify"},
    {"diagnose"},
    {"paper", "cohort", "evaluation", "design"},
    {"cli", "commands", "__main__", "__init__"},
]
LAYER_OF = {name: i for i, layer in enumerate(LAYERS) for name in layer}


def module_name(path: Path, root: Path = SRC) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports_of(path: Path, root: Path = SRC) -> set:
    """Absolute names of the skinsuction modules ``path`` imports (anywhere in it)."""
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("skinsuction")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.startswith("skinsuction"):
                out.add(mod)
                out |= {f"{mod}.{a.name}" for a in node.names}
    return out


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def top(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_every_top_level_module_has_a_layer():
    assert {top(m) for m in MODULES} <= set(LAYER_OF), {top(m) for m in MODULES} - set(LAYER_OF)


def upward(name: str, path: Path, root: Path = SRC) -> list:
    """The imports of module ``name`` that reach a higher layer than its own."""
    mine = LAYER_OF[top(name)]
    return sorted(m for m in imports_of(path, root)
                  if top(m) != "__init__" and LAYER_OF.get(top(m), -1) > mine)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_imports_go_down_the_layers(name):
    if name == "skinsuction":  # the lazy flat API may name any layer
        return
    up = upward(name, MODULES[name])
    assert not up, f"{name} (layer {LAYER_OF[top(name)]}) imports from a higher layer: {up}"


def private_of_another(name: str, path: Path, root: Path = SRC) -> list:
    """The private modules of other subpackages that module ``name`` imports: a
    ``skinsuction.<package>._<module>`` (or a name in one) whose package is not its
    own.  The shared helpers (``skinsuction._files`` ...) belong to no subpackage."""
    mine = name.split(".")[1] if name.count(".") else ""
    out = set()
    for m in imports_of(path, root):
        parts = m.split(".")
        if (len(parts) > 2 and parts[1] != mine and (root / "skinsuction" / parts[1]).is_dir()
                and parts[2].startswith("_") and not parts[2].startswith("__")):
            out.add(".".join(parts[:3]))
    return sorted(out)


#: imports of another subpackage's private module made before the rule was checked:
#: each is a public name its package should export (module -> private modules)
PRIVATE_IMPORT_DEBTS = {}  # every debt paid: public names only


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_imports_a_private_module_of_another_subpackage(name):
    # a subpackage's face is its __init__ (and its public modules): what its private
    # modules hold may move without notice, so the other packages import public names
    found = set(private_of_another(name, MODULES[name])) - PRIVATE_IMPORT_DEBTS.get(name, set())
    assert not found, f"{name} imports private modules of other subpackages: {sorted(found)}"


def test_the_private_import_checker_sees_one(tmp_path):
    fake = tmp_path / "skinsuction" / "commands" / "x.py"
    fake.parent.mkdir(parents=True)
    for sub in ("measured", "identify"):
        (tmp_path / "skinsuction" / sub).mkdir()
    fake.write_text("from skinsuction.measured._geometry import SD_KEYS\n"
                    "from skinsuction._files import atomic_output\n"
                    "from skinsuction.identify import Interval\n"
                    "from ._common import CLIError\n")
    assert private_of_another("skinsuction.commands.x", fake, tmp_path) == [
        "skinsuction.measured._geometry"]


def find_circle(graph: dict):
    """A list of nodes closing a circle of ``graph`` ({node: targets}), or None."""
    state, path = {}, []

    def visit(n):
        state[n] = "open"
        path.append(n)
        for t in sorted(graph.get(n, ())):
            if state.get(t) == "open":
                return path[path.index(t):] + [t]
            if t not in state:
                found = visit(t)
                if found:
                    return found
        path.pop()
        state[n] = "done"
        return None

    for n in sorted(graph):
        if n not in state:
            found = visit(n)
            if found:
                return found
    return None


def test_no_import_circle_between_modules():
    graph = {}
    for name, path in MODULES.items():
        targets = set()
        for m in imports_of(path):
            while m and m not in MODULES:  # "pkg.name" of a re-exported name: the package
                m = m.rpartition(".")[0]
            # a package's modules importing their own package's __init__ is not a circle
            # of the design (the __init__ only re-exports them)
            if m and m != name and not name.startswith(m + "."):
                targets.add(m)
        graph[name] = targets
    assert find_circle(graph) is None, " -> ".join(find_circle(graph))
    assert find_circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def test_the_checker_sees_an_upward_import(tmp_path):
    # the rule can fail: a model module importing the space, absolutely or relatively,
    # inside a function or not, is refused; importing its own layer is not
    fake = tmp_path / "skinsuction" / "model" / "_x.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("from skinsuction.errors import InputError\n"
                    "def f():\n    from ..space import read_space\n")
    assert upward("skinsuction.model._x", fake, tmp_path) == [
        "skinsuction.space", "skinsuction.space.read_space"]
    fake.write_text("from ._curve import Curve\nfrom skinsuction import errors\n")
    assert upward("skinsuction.model._x", fake, tmp_path) == []


def test_an_fe_job_imports_nothing_above_the_space():
    # the layers hold at run time too: an FE job (the code of simulate_row and
    # simulate_ray_bundle) must not import identification or diagnosis through the
    # package's lazy flat API (`from skinsuction import model` once imported
    # skinsuction.identify and SciPy's stats: 0.3 s of every FE job)
    import os
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from skinsuction.jobs import job\n"  # the preamble of every workflow script
        "from skinsuction.space import compute_point, compute_points, compute_bundle\n"
        "from skinsuction import model\n"
        "import skinsuction.space._solve, skinsuction.space._ray_solve\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(SRC)})
    loaded = set(out.stdout.split())
    assert "skinsuction.model" in loaded and "skinsuction.space" in loaded
    above = {m for m in loaded if m.split(".")[:2][-1] in {
        "identify", "diagnose", "paper", "cohort", "cli", "commands", "figures"}}
    assert not above, above
    assert "scipy.stats" not in loaded


# ------------------------------------------------------------- the workflow's scripts
SCRIPTS = sorted((ROOT / "workflow" / "scripts").glob("*.py"))


def private_imports(path: Path) -> list:
    """The private skinsuction names a script imports: a module or name below
    ``skinsuction`` whose part starts with ``_`` (``skinsuction._files``,
    ``skinsuction.diagnose._time``, ``from skinsuction.space import _rays``); dunders
    such as ``__version__`` are public."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # a script is no package: a relative import is refused too
                out.append("." * node.level + (node.module or ""))
                continue
            names = [node.module or ""] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "skinsuction" and any(
                    p.startswith("_") and not (p.startswith("__") and p.endswith("__"))
                    for p in parts[1:]):
                out.append(name)
    return sorted(set(out))


def test_every_workflow_script_is_checked():
    assert len(SCRIPTS) >= 20 and ROOT / "workflow" / "scripts" / "simulate_row.py" in SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_workflow_scripts_import_public_names_only(script):
    # a script is a thin adapter of the package's public face: a private module it
    # imports could change or move without its package's own tests noticing
    private = private_imports(script)
    assert not private, f"{script.name} imports private names: {private}"


def test_the_script_checker_sees_a_private_import(tmp_path):
    script = tmp_path / "s.py"
    script.write_text("from skinsuction._threads import limit_threads\n"
                      "import skinsuction.space._rays\n"
                      "with job(log):\n"
                      "    from skinsuction.diagnose import _confusion, Settings\n"
                      "    from skinsuction import __version__, jobs\n")
    assert private_imports(script) == ["skinsuction._threads", "skinsuction._threads.limit_threads",
                                       "skinsuction.diagnose._confusion",
                                       "skinsuction.space._rays"]
    script.write_text("from skinsuction.jobs import job, write_table\n")
    assert private_imports(script) == []


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_workflow_scripts_start_with_the_shared_preamble(script):
    # `with job(snakemake.log[0], ...)` is the script's one top-level block, and before
    # it only the standard library and skinsuction.jobs are imported: the thread pools
    # are sized before NumPy loads, and all output goes to the rule's log
    body = ast.parse(script.read_text(encoding="utf-8")).body
    blocks = [n for n in body if isinstance(n, ast.With)]
    assert len(blocks) == 1, script.name
    call = blocks[0].items[0].context_expr
    assert isinstance(call, ast.Call) and getattr(call.func, "id", None) == "job", script.name
    assert ast.unparse(call.args[0]) == "snakemake.log[0]", script.name
    before = body[:body.index(blocks[0])]
    for node in before:
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            continue  # the docstring
        assert isinstance(node, (ast.Import, ast.ImportFrom)), (script.name, ast.unparse(node))
        module = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
        assert module == "skinsuction.jobs" or module.split(".")[0] in {
            "logging", "pathlib", "json", "sys"}, (script.name, module)
    assert blocks[0] is body[-1], f"{script.name}: code after the job's block"


def test_the_preamble_loads_no_numpy():
    # skinsuction.jobs is imported before the thread pools are sized: NumPy must not be
    import os
    import subprocess
    import sys

    code = "import sys, skinsuction.jobs\nprint('numpy' in sys.modules)\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(SRC)})
    assert out.stdout.strip() == "False"
