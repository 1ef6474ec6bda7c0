"""The package has the shape of its data flow, and it stays that way.

Layers are enforced by import-linter (contracts in pyproject.toml); these tests run it,
check what importing the light layers drags in (in a fresh interpreter), walk the import
graph for cycles, and count that one build solves the theoretical screw diameter once.
"""
from __future__ import annotations

import ast
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "prs_geom"
HEAVY = ("trimesh", "fcl", "manifold3d", "ezdxf", "matplotlib", "openpyxl")


def _loaded_after(statement: str) -> list[str]:
    code = (f"import sys, json; {statement}; "
            f"print(json.dumps(sorted(m for m in {list(HEAVY)!r} if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(out.stdout)


def test_import_linter_contracts_are_kept():
    exe = shutil.which("lint-imports", path=str(Path(sys.executable).parent)) or shutil.which("lint-imports")
    assert exe, "import-linter is part of the test extra"
    r = subprocess.run([exe, "--no-cache"], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "0 broken" in r.stdout and "6 kept" in r.stdout


def _contract_names() -> set[str]:
    """Every module or package some import-linter contract of pyproject.toml names."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    named: set[str] = set()
    for contract in config["tool"]["importlinter"]["contracts"]:
        for key in ("layers", "source_modules", "forbidden_modules", "modules"):
            for entry in contract.get(key, []):
                # a layer may hold independent siblings "a : b", and optional ones in parentheses
                named.update(part.strip().strip("()") for part in entry.split(":"))
    return named


def test_every_module_is_under_a_contract():
    """A module counts as named when it or a package above it appears in a contract: a new
    module outside every contract fails here, naming it."""
    import pkgutil

    import prs_geom

    named = _contract_names()
    modules = [m.name for m in pkgutil.walk_packages(prs_geom.__path__, "prs_geom.")]
    assert len(modules) > 30

    def covered(name: str) -> bool:
        parts = name.split(".")
        return any(".".join(parts[:k]) in named for k in range(2, len(parts) + 1))

    assert [m for m in modules if not covered(m)] == []


def test_analysis_imports_no_mesh_library():
    stmt = ("import prs_geom.analysis, prs_geom.analysis.contact, prs_geom.analysis.loads, "
            "prs_geom.analysis.load_solver, prs_geom.analysis.machining, prs_geom.geometry.sections")
    assert _loaded_after(stmt) == []


def test_package_import_is_light_and_the_api_loads_on_use():
    assert _loaded_after("import prs_geom") == []
    assert _loaded_after("import prs_geom as pg; pg.default_design(); pg.DesignError") == []
    assert "trimesh" in _loaded_after("import prs_geom as pg; pg.build_meshes(pg.default_design(), tol=0.1)")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """Module -> package modules it imports (any depth in the file, absolute or relative)."""
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for mod, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        pkg = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
        for node in ast.walk(tree):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                targets = [base] + [f"{base}.{a.name}" for a in node.names]
            for t in targets:
                while t and t not in modules:
                    t = t.rsplit(".", 1)[0] if "." in t else ""
                if t and t != mod:
                    graph[mod].add(t)
    return graph


def test_no_import_cycle():
    graph = import_graph()
    assert len(graph) > 30
    # Tarjan's strongly connected components: any component of two or more is a cycle
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    # the package __init__ names modules lazily (strings), so it is no edge; nothing else may cycle
    assert cycles == []


def test_every_subpackage_says_what_it_owns():
    for init in PACKAGE.glob("*/__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8")))
        assert doc and len(doc) > 60, init


def test_theoretical_diameter_is_solved_once_per_build(tmp_path, monkeypatch):
    from prs_geom.analysis import contact
    from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread
    from prs_geom.pipeline import build

    calls = []
    real = contact.theoretical_screw

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    for mod in list(sys.modules.values()):
        if getattr(mod, "__name__", "").startswith("prs_geom") and getattr(mod, "theoretical_screw", None) is real:
            monkeypatch.setattr(mod, "theoretical_screw", counted)
    d = PRSDesign(name="once", thread=Thread(engaged_teeth=4), roller=Roller(count=3),
                  mesh=MeshSettings(chord_tolerance_mm=0.05))
    build(d, tmp_path / "out", memory_budget=4 * 2 ** 30)
    assert len(calls) == 1


@pytest.mark.parametrize("needle", ['== "arc"', "== 'arc'", "FLANK_ARC", 'flank == "straight"'])
def test_flank_shape_is_an_object_not_a_string_switch(needle):
    """The flank kind is chosen once, where profiles are built from the design; everything
    else asks the flank object."""
    hits = [str(p.relative_to(ROOT)) for p in PACKAGE.rglob("*.py") if needle in p.read_text(encoding="utf-8")]
    assert hits == []


def test_docs_build_strict_without_warnings(tmp_path):
    """The site (theory pages, CLI, report, API reference from the docstrings) builds with
    warnings as errors."""
    exe = shutil.which("mkdocs", path=str(Path(sys.executable).parent)) or shutil.which("mkdocs")
    assert exe, "mkdocs is part of the test extra"
    r = subprocess.run([exe, "build", "--strict", "--site-dir", str(tmp_path / "site")], capture_output=True,
                       text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "WARNING" not in r.stderr
    page = (tmp_path / "site" / "reference" / "analysis" / "index.html").read_text(encoding="utf-8")
    assert "theoretical_screw_pitch_diameter_mm" in page and "ContactResult" in page
    # the reference documents a module's __all__ and nothing else: the pipeline's API names
    # are there, its stage functions and build context are not
    import re

    import prs_geom.pipeline as pipeline

    page = (tmp_path / "site" / "reference" / "pipeline" / "index.html").read_text(encoding="utf-8")
    documented = set(re.findall(r'id="prs_geom\.pipeline\.([A-Za-z_]+)"', page))
    assert documented == set(pipeline.__all__) - {"REPORT_NAME", "DESIGN_KINDS"} | (documented & {"REPORT_NAME", "DESIGN_KINDS"})
    assert not documented & {"BuildContext", "checks_job", "stage_meshes", "run_stages"}


def test_readme_and_docs_stand_alone():
    """README links docs/, every relative link resolves inside the repository, and nothing
    points at the notes outside it."""
    import re

    for md in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        text = md.read_text(encoding="utf-8")
        assert "../shared" not in text and "DOMAIN.md" not in text, md
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if "://" in target:
                continue
            path = (md.parent / target).resolve()
            assert path.exists() and ROOT in path.parents, (md.name, target)
    assert "docs/index.md" in (ROOT / "README.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("argv", [["--help"], ["init"], ["build", "--help"], ["rating", "--help"]])
def test_help_and_init_import_no_heavy_library(argv):
    """``prs-geom --help`` and ``prs-geom init`` answer without loading trimesh,
    fcl, manifold3d, ezdxf, matplotlib or openpyxl (their import alone costs seconds)."""
    stmt = ("import contextlib, io; from prs_geom import cli\n"
            f"with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    try: cli.main({argv!r})\n"
            f"    except SystemExit: pass")
    code = (f"import sys, json\n{stmt}\n"
            f"print(json.dumps(sorted(m for m in {list(HEAVY)!r} if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
