"""Code health the next maintainer can rely on, measured on the source.

- No function in the package is longer than :data:`MAX_FUNCTION_LINES` lines, except the ones
  on :data:`LONG_FUNCTION_ALLOW_LIST`, each with the reason it is waiting; an entry that is
  no longer long fails too, so the list only shrinks.
- Every module states its public names in ``__all__``, and every listed name exists.
- pylint's similarity engine (six or more similar lines, as its duplicate-code check)
  reports nothing.
"""
from __future__ import annotations

import ast
import contextlib
import io
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "prs_geom"
MODULES = sorted(PACKAGE.rglob("*.py"))

#: A function's length: from its ``def`` (decorators not counted) to its last line.
MAX_FUNCTION_LINES = 80

#: (module path relative to the package, function name or "*" for the whole module) -> why it
#: may stay long for now. Empty: the drawings, the mechanism layout and the gear mesh, which
#: waited here for the complete-parts and shop-drawing work, are split into named steps.
LONG_FUNCTION_ALLOW_LIST: dict[tuple[str, str], str] = {}


def _functions(path: Path) -> list[tuple[str, int, int]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [(node.name, node.lineno, node.end_lineno - node.lineno + 1) for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def _allowed(rel: str, name: str) -> bool:
    return (rel, name) in LONG_FUNCTION_ALLOW_LIST or (rel, "*") in LONG_FUNCTION_ALLOW_LIST


def test_no_function_is_longer_than_the_limit():
    long = [f"prs_geom/{path.relative_to(PACKAGE).as_posix()}:{line} {name}: {length} lines"
            for path in MODULES for name, line, length in _functions(path)
            if length > MAX_FUNCTION_LINES and not _allowed(path.relative_to(PACKAGE).as_posix(), name)]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines (split them into named steps):\n" + "\n".join(long)


def test_allow_list_holds_only_long_functions():
    stale = []
    for (rel, name), _why in LONG_FUNCTION_ALLOW_LIST.items():
        path = PACKAGE / rel
        assert path.is_file(), f"allow-list names a missing module: {rel}"
        lengths = [length for fn, _line, length in _functions(path) if name in ("*", fn)]
        assert lengths, f"allow-list names a missing function: {rel} {name}"
        if max(lengths) <= MAX_FUNCTION_LINES:
            stale.append(f"{rel} {name}")
    assert not stale, "no longer long, remove from the allow-list: " + ", ".join(stale)


def test_the_length_rule_finds_a_long_function(tmp_path):
    src = tmp_path / "m.py"
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_FUNCTION_LINES))
    src.write_text(f"def short():\n    return 1\n\n\ndef long():\n{body}\n    return 0\n")
    lengths = {name: length for name, _line, length in _functions(src)}
    assert lengths == {"short": 2, "long": MAX_FUNCTION_LINES + 2}


def _declares_all(tree: ast.Module) -> bool:
    """Whether the module body assigns ``__all__`` (its content is checked by importing)."""
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            return True
    return False


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_every_module_declares_its_public_names():
    missing = [_module_name(p) for p in MODULES if not _declares_all(ast.parse(p.read_text(encoding="utf-8")))]
    assert not missing, "modules without __all__:\n" + "\n".join(missing)


@pytest.mark.parametrize("path", MODULES, ids=_module_name)
def test_every_public_name_exists(path):
    import importlib

    module = importlib.import_module(_module_name(path))
    names = getattr(module, "__all__", None)
    assert names is not None, f"{module.__name__} has no __all__"
    assert len(set(names)) == len(names), f"{module.__name__}.__all__ lists a name twice"
    absent = [n for n in names if not hasattr(module, n)]
    assert not absent, f"{module.__name__}.__all__ lists names it does not define: {absent}"


def _without_imports_and_signatures(source: str) -> str:
    """``source`` with its import statements and function signatures (``def`` line to the
    line before the body) as empty lines, which the similarity engine skips: what pylint's
    ``ignore-imports`` and ``ignore-signatures`` drop, found by Python's own parser."""
    blank: set[int] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            blank.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            blank.update(range(node.lineno, node.body[0].lineno))
    return "".join("\n" if i in blank else line for i, line in enumerate(source.splitlines(keepends=True), 1))


def similar_code(files: list[Path], min_lines: int = 6) -> str:
    """pylint's similarity engine (``Symilar``, the ``duplicate-code`` check's) on ``files``,
    comments and docstrings ignored, imports and signatures blanked
    (:func:`_without_imports_and_signatures`): its report of every block of more than
    ``min_lines`` similar lines, empty when there is none.

    pylint itself (``--enable=duplicate-code``) gives the same verdict but first builds an
    astroid tree of every module, 42 s of the suite's 10 minutes for what takes 0.5 s here."""
    from pylint.checkers.symilar import Symilar

    engine = Symilar(min_lines=min_lines, ignore_comments=True, ignore_docstrings=True)
    for path in files:
        engine.append_stream(str(path), io.StringIO(_without_imports_and_signatures(path.read_text(encoding="utf-8"))))
    report = io.StringIO()
    with contextlib.redirect_stdout(report):
        engine.run()
    # the report ends "TOTAL lines=N duplicates=D percent=P"
    found = re.search(r"\bduplicates=(\d+)", report.getvalue())
    assert found, report.getvalue()[-500:]
    return report.getvalue() if int(found.group(1)) else ""


def test_no_duplicate_code():
    """Six or more lines of the same shape in two places of the package are one helper
    waiting to be written (:func:`similar_code`)."""
    report = similar_code(MODULES)
    assert report == "", report[-4000:]


def test_the_duplicate_check_finds_a_copied_block_but_not_imports_or_signatures(tmp_path):
    """Two modules with the same eight-line function body (under different names), the same
    import block and the same seven-line signature layout: only the body is reported."""
    header = "".join(f"import {m}\n" for m in ("os", "sys", "json", "math", "time", "shutil", "pathlib"))
    body = ("    acc = []\n    for v in values:\n        if v > 3:\n            acc.append(v * 2)\n"
            "        else:\n            acc.append(-v)\n    acc.sort()\n    acc.reverse()\n    return acc[:5]\n")
    for name in ("a", "b"):
        signature = f"def {name}_sig(x,\n" + "".join(f"        {p},\n" for p in "yzwvu") + "        t):\n"
        (tmp_path / f"{name}.py").write_text(f"{header}\n\n{signature}    return x + {name!r}\n\n\n"
                                             f"def {name}_body(values):\n{body}", encoding="utf-8")
    files = sorted(tmp_path.glob("*.py"))
    report = similar_code(files)
    assert "duplicates=9" in report and "acc.reverse()" in report and "import" not in report
    (tmp_path / "b.py").write_text((tmp_path / "b.py").read_text().replace("acc.sort()", "acc.clear()")
                                   .replace("acc.reverse()", "acc.pop()"), encoding="utf-8")
    assert similar_code(files) == ""


def _string_key_reads(tree: ast.AST) -> list[ast.Subscript]:
    """Every ``x["key"]`` read (a subscript by a string constant, in load context)."""
    return [node for node in ast.walk(tree) if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Load)
            and isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str)]


def test_the_build_reads_no_report_dict():
    """The stages pass typed results on; report.json is rendered at the end
    (prs_geom.exports.report). No function of the pipeline reads a value out of a dict by a
    string key (``rep["passed"]``), the way a stage reading a report section back would."""
    tree = ast.parse((PACKAGE / "pipeline.py").read_text(encoding="utf-8"))
    reads = [f"pipeline.py:{node.lineno} [{node.slice.value!r}]" for node in _string_key_reads(tree)]
    assert not reads, "string-key reads in the pipeline:\n" + "\n".join(reads)


def test_the_report_dict_rule_finds_a_read():
    tree = ast.parse('def stage(ctx):\n    rep = ctx.report\n    if not rep["passed"]:\n        pass\n')
    assert [node.slice.value for node in _string_key_reads(tree)] == ["passed"]
