"""Every name of the top-level API carries a runnable example in its docstring, and the
examples run (doctest, with the output they show compared)."""
from __future__ import annotations

import doctest
import os

import pytest

import prs_geom

API_NAMES = sorted(n for n in prs_geom.__all__ if n != "__version__")

pytestmark = pytest.mark.docs


@pytest.mark.parametrize("name", API_NAMES)
def test_api_name_has_a_runnable_example(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    import prs_geom.sweep  # noqa: F401  (a submodule bound on the package must not shadow an API name)

    obj = getattr(prs_geom, name)
    assert callable(obj) and not isinstance(obj, type(prs_geom)), f"prs_geom.{name} is a module, not the API object"
    tests = [t for t in doctest.DocTestFinder(recurse=False).find(obj, name, globs={"pg": prs_geom})
             if t.examples]
    assert tests, f"prs_geom.{name} has no example in its docstring"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"prs_geom.{name}: {result.failed} of {result.attempted} examples failed (see above)"
