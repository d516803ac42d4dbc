"""The package's layers import one way, and no module imports itself back.

Layers, lowest first (docs/workflow.md#layout): the shared helpers, the model,
its viscoelastic extension, the simulated space, the figures (drawing plain tables), identify, diagnose,
then the studies (paper, cohort, and evaluation: the study of the method) and the
command line.  A module may import from its own layer and the layers below, never
from above, so the forward model knows nothing of spaces and neither the paper's
study nor the evaluation of the method is needed to identify or diagnose a curve.  Imports inside functions count: they are arrows too.
"""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "skinsuction"

LAYERS = [
    {"errors", "_files", "_threads", "_argtypes", "_progress", "provenance", "noise", "config",
     "measured"},
    {"model"},
    {"viscoelastic"},
    {"space"},
    {"figures"},
    {"identify"},
    {"diagnose"},
    {"paper", "cohort", "evaluation"},
    {"cli", "__main__", "__init__"},
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
    # the layers hold at run time too: an FE job (the code of simulate_point and
    # simulate_ray_bundle) must not import identification or diagnosis through the
    # package's lazy flat API (`from skinsuction import model` once imported
    # skinsuction.identify and SciPy's stats: 0.3 s of every FE job)
    import os
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from skinsuction.space import compute_point, compute_bundle\n"
        "from skinsuction import model\n"
        "import skinsuction.space._solve, skinsuction.space._ray_solve\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(SRC)})
    loaded = set(out.stdout.split())
    assert "skinsuction.model" in loaded and "skinsuction.space" in loaded
    above = {m for m in loaded if m.split(".")[:2][-1] in {
        "identify", "diagnose", "paper", "cohort", "cli", "figures"}}
    assert not above, above
    assert "scipy.stats" not in loaded
