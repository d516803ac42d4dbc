"""Every ``>>>`` example of the package runs and gives what it shows.

The docstrings are the users' first documentation (FElupe's and scikit-fem's
style): an example that no test runs drifts from the code.  One test per
module, so a failure names the module.
"""

import doctest
import importlib
import pkgutil

import matplotlib
import pytest

import skinsuction

matplotlib.use("Agg")

MODULES = sorted(
    m.name for m in pkgutil.walk_packages(skinsuction.__path__, "skinsuction.")
    if not m.name.endswith("__main__")
)


def test_every_module_is_listed():
    # the walk itself must see the package's layers, or the test below is empty
    for name in ("skinsuction.space._rays", "skinsuction.identify._objectives",
                 "skinsuction.paper._figures", "skinsuction.measured"):
        assert name in MODULES


@pytest.mark.parametrize("name", ["skinsuction.model._geometry", "skinsuction.model._material",
                                  "skinsuction.model._probe", "skinsuction.model._simulate",
                                  "skinsuction.space", "skinsuction.identify",
                                  "skinsuction.measured", "skinsuction.paper"])
def test_the_main_modules_have_examples(name):
    finder = doctest.DocTestFinder()
    examples = sum(len(t.examples) for t in finder.find(importlib.import_module(name)))
    assert examples > 0, f"{name} shows no example"


@pytest.mark.parametrize("name", MODULES)
def test_examples(name, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    plt.close("all")
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"
