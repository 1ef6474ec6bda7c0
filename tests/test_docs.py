"""The documentation as a reader sees it.

Every page under docs/ is rendered with the Python ``markdown`` package, with the extensions
and settings of mkdocs.yml (read from it, so the two cannot drift apart) plus the ones MkDocs
always adds, and the result is checked for Markdown that did not render: headings that are
really a table row or a code fence, tables that stayed text or whose rows have the wrong
number of cells, unclosed code fences and other syntax left visible in the text. Each
problem is reported as ``file:line: what``.

The checker is tried on small pages with known defects (tests/data/docs_broken/), so a
clean result on the real pages means something. The other tests keep the command-line
reference complete against the argparse parser and the overview linked to every theory
page. (``mkdocs build --strict`` itself runs in tests/test_architecture.py.)
"""
from __future__ import annotations

import argparse
import difflib
import functools
import re
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path

import markdown
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BROKEN = Path(__file__).resolve().parent / "data" / "docs_broken"
PAGES = sorted(DOCS.rglob("*.md"))


# --------------------------------------------------------------------------- the renderer
class _TolerantLoader(yaml.SafeLoader):
    """mkdocs.yml may carry MkDocs' own tags (``!ENV``, ``!!python/name:``); they are read as
    plain values, since only the Markdown settings matter here."""


_TolerantLoader.add_multi_constructor("!", lambda loader, suffix, node: None)
_TolerantLoader.add_multi_constructor("tag:yaml.org,2002:python/", lambda loader, suffix, node: None)


def markdown_settings() -> tuple[list[str], dict[str, dict]]:
    """The extension names and their settings a MkDocs build of this site renders with: the
    ones MkDocs always adds (``toc``, ``tables``, ``fenced_code``) and those of
    mkdocs.yml ``markdown_extensions``, with their options as written there."""
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=_TolerantLoader)
    try:
        from mkdocs.config.defaults import MkDocsConfig

        names = list(MkDocsConfig.markdown_extensions.builtins)
    except (ImportError, AttributeError):  # pragma: no cover - MkDocs 1.6 has it
        names = ["toc", "tables", "fenced_code"]
    settings: dict[str, dict] = {}
    for item in config.get("markdown_extensions") or []:
        if isinstance(item, str):
            name, options = item, {}
        else:
            ((name, options),) = item.items()
        if name not in names:
            names.append(name)
        settings[name] = dict(options or {})
    return names, settings


def render(text: str) -> str:
    names, settings = markdown_settings()
    return markdown.Markdown(extensions=names, extension_configs=settings).convert(text)


# --------------------------------------------------------------------------- problems
@dataclass(frozen=True, order=True)
class Problem:
    path: str
    line: int
    message: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.message}"


# --------------------------------------------------------------------------- source scan
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})(.*)$")
ATX = re.compile(r"^(#{1,6})(?!#)(.*?)(?:\s+#+)?\s*$")  # Python-Markdown needs no space after '#'
#: a table row: starts with '|' and ends with one or has a cell border ' | ' (a line that only
#: starts with an absolute value such as '|x - y| is ...' is prose)
TABLE_LINE = re.compile(r"^ {0,3}\|(?:.*\|\s*$|.*\s\|\s)")
SEPARATOR_CELL = re.compile(r"^\s*:?-+:?\s*$")
CODE_LIKE = ("|", "```", "~~~")


def table_cells(line: str) -> list[str]:
    """The cells of a table row as the tables extension splits them: on ``|`` that is
    neither escaped (``\\|``) nor inside a code span; an outer pipe on either end is a
    border, not a cell."""
    text = line.strip()
    cells: list[str] = []
    current: list[str] = []
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "\\" and i + 1 < len(text):
            current.append(text[i:i + 2])
            i += 2
            continue
        if ch == "`":
            run = len(text[i:]) - len(text[i:].lstrip("`"))
            ticks = "`" * run
            # a code span runs to the next run of exactly as many backticks
            end = i + run
            close = -1
            while True:
                k = text.find(ticks, end)
                if k < 0:
                    break
                after = k + run
                if (k == 0 or text[k - 1] != "`") and (after >= len(text) or text[after] != "`"):
                    close = k
                    break
                end = k + 1
            if close >= 0:
                current.append(text[i:close + run])
                i = close + run
            else:
                current.append(ticks)
                i += run
            continue
        if ch == "|":
            cells.append("".join(current))
            current = []
        else:
            current.append(ch)
        i += 1
    cells.append("".join(current))
    if text.startswith("|"):
        cells = cells[1:]
    if len(text) > 1 and text.endswith("|") and not text.endswith("\\|") and cells:
        cells = cells[:-1]
    return cells


def is_separator(line: str) -> bool:
    cells = table_cells(line)
    return bool(cells) and all(SEPARATOR_CELL.match(c) for c in cells)


@dataclass
class SourceScan:
    """What the Markdown source holds, line by line (1-based numbers)."""
    lines: list[str]
    in_code: list[bool] = field(default_factory=list)  # inside a fence or a $$ block
    tables: list[list[tuple[int, str]]] = field(default_factory=list)
    problems: list[tuple[int, str]] = field(default_factory=list)


def fence_pairs(lines: list[str]) -> tuple[dict[int, int], list[int]]:
    """Code fences as Python-Markdown pairs them: opening line -> closing line (0-based), and
    the fence lines that open a fence never closed (those are text, so the lines after them
    are paired again without them)."""
    pairs: dict[int, int] = {}
    unclosed: list[int] = []
    start = 0
    while True:
        open_at: int | None = None
        for i in range(start, len(lines)):
            m = FENCE.match(lines[i])
            if not m:
                continue
            if open_at is None:
                open_at, char, length = i, m[1][0], len(m[1])
            elif m[1][0] == char and len(m[1]) >= length and not m[2].strip():
                pairs[open_at] = i
                open_at = None
        if open_at is None:
            return pairs, unclosed
        unclosed.append(open_at)
        start = open_at + 1


def scan_source(text: str) -> SourceScan:
    lines = text.splitlines()
    scan = SourceScan(lines)
    pairs, unclosed = fence_pairs(lines)
    fence_end = -1
    math = False
    block: list[tuple[int, str]] = []
    for i, line in enumerate(lines):
        number = i + 1
        if i <= fence_end or i in pairs:
            fence_end = max(fence_end, pairs.get(i, -1))
            scan.in_code.append(True)
            if block:
                scan.tables.append(block)
                block = []
            continue
        stripped = line.strip()
        if math or stripped.startswith("$$"):
            scan.in_code.append(True)
            if not math:
                math = stripped == "$$" or not (len(stripped) >= 4 and stripped.endswith("$$"))
            elif stripped.endswith("$$"):
                math = False
            continue
        scan.in_code.append(False)
        if TABLE_LINE.match(line):
            block.append((number, line))
            continue
        if block:
            scan.tables.append(block)
            block = []
        h = ATX.match(line)
        if h and h[2].strip().startswith(CODE_LIKE):
            kind = "a table row" if h[2].strip().startswith("|") else "a code fence"
            scan.problems.append((number, f"heading whose text is really {kind}: {line.strip()!r} "
                                          f"(a stray '#' before the line?)"))
    if block:
        scan.tables.append(block)
    for i in unclosed:
        fence = FENCE.match(lines[i])[1]
        scan.problems.append((i + 1, f"code fence {fence} is never closed (an odd number of fence "
                                     f"lines): what follows shows as text"))
    for table in scan.tables:
        number, first = table[0]
        if is_separator(first):
            scan.problems.append((number, "table starts with its separator row: the header line is missing "
                                          "or was swallowed by the line above (e.g. a heading)"))
            continue
        if len(table) < 2 or not is_separator(table[1][1]):
            scan.problems.append((number, "lines starting with '|' without a separator row (| --- | ...) "
                                          "under the first: they render as text, not as a table"))
            continue
        width = len(table_cells(first))
        for row_number, row in table[1:]:
            n = len(table_cells(row))
            if n != width:
                scan.problems.append((row_number, f"table row has {n} cells, its header {width} (an unescaped "
                                                  f"'|' in a cell, e.g. inside $...$, or a missing one?)"))
    return scan


# --------------------------------------------------------------------------- rendered HTML
VOID = {"br", "hr", "img", "input", "meta", "link", "wbr"}
BLOCKS = {"p", "li", "td", "th", "dt", "dd", "h1", "h2", "h3", "h4", "h5", "h6"}
NESTED_BLOCKS = BLOCKS | {"ul", "ol", "dl", "table", "div", "pre", "blockquote", "details"}
HEADINGS = {"h1", "h2", "h3", "h4", "h5", "h6"}


@dataclass
class Node:
    tag: str
    attrs: dict[str, str]
    children: list["Node | str"] = field(default_factory=list)

    def classes(self) -> set[str]:
        return set((self.attrs.get("class") or "").split())

    def walk(self):
        yield self
        for c in self.children:
            if isinstance(c, Node):
                yield from c.walk()


class _TreeBuilder(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.root = Node("root", {})
        self.stack = [self.root]

    def handle_starttag(self, tag, attrs):
        node = Node(tag, {k: v or "" for k, v in attrs})
        self.stack[-1].children.append(node)
        if tag not in VOID:
            self.stack.append(node)

    def handle_startendtag(self, tag, attrs):
        self.stack[-1].children.append(Node(tag, {k: v or "" for k, v in attrs}))

    def handle_endtag(self, tag):
        for k in range(len(self.stack) - 1, 0, -1):
            if self.stack[k].tag == tag:
                del self.stack[k:]
                break

    def handle_data(self, data):
        self.stack[-1].children.append(data)


def parse_html(html: str) -> Node:
    builder = _TreeBuilder()
    builder.feed(html)
    builder.close()
    return builder.root


def inline_text(node: Node) -> tuple[str, str]:
    """(shown, masked) text of a block element's own inline content: nested blocks are left
    out, the permalink anchor too; in ``masked`` every character of code and math is an
    ``x``, so Markdown syntax found there is syntax a reader sees outside code."""
    shown: list[str] = []
    masked: list[str] = []

    def visit(n: Node, hidden: bool) -> None:
        for c in n.children:
            if isinstance(c, str):
                shown.append(c)
                masked.append(re.sub(r"\S", "x", c) if hidden else c)
            elif c.tag in NESTED_BLOCKS or "headerlink" in c.classes():
                continue
            elif c.tag == "br":
                shown.append("\n")
                masked.append("\n")
            else:
                visit(c, hidden or c.tag in ("code", "kbd", "samp") or "arithmatex" in c.classes())

    visit(node, False)
    return "".join(shown), "".join(masked)


#: Markdown syntax that, seen in rendered text outside code and math, did not render.
LEAKS: list[tuple[re.Pattern[str], str]] = [
    (re.compile(r"^\s*\|(?:.*\|\s*$|.*\s\|\s)"), "a table row shows as text (these lines did not become a <table>)"),
    (re.compile(r"\|\s*:?-{3,}:?\s*\|"), "a table separator row (|---|) shows as text"),
    (re.compile(r"```|~~~"), "a code fence shows as text (unclosed or broken fence)"),
    (re.compile(r"^\s*#{1,6}\s+\S"), "a heading marker '#' shows as text"),
    (re.compile(r"^\s*!!!\s*\w"), "an admonition marker '!!!' shows as text"),
    (re.compile(r"\]\([^)\s]*\)"), "link syntax [text](target) shows as text"),
    (re.compile(r"\*\*|(?<![\w])__(?=\w)"), "emphasis markers show as text"),
    (re.compile(r"\$\$"), "display-math delimiters $$ show as text"),
]


def _norm(text: str) -> str:
    """Text reduced to what source and rendering share: no link targets, emphasis or code
    markers, escapes or math delimiters, single spaces."""
    text = re.sub(r"\]\([^)]*\)", "]", text)
    text = re.sub(r"^#{1,6}", "", text.strip())
    text = re.sub(r"\\[()\[\]]", "", text)
    text = re.sub(r"[`*_\\\[\]$]", "", text)
    return " ".join(text.split())


class _Locator:
    """Finds the source line a piece of rendered text came from, searching forward from a
    given line first (elements are visited in document order)."""

    def __init__(self, scan: SourceScan) -> None:
        self.scan = scan
        self.norm = [_norm(line) for line in scan.lines]
        self.raw = [" ".join(line.split()) for line in scan.lines]

    def find(self, rendered: str, start: int = 0) -> tuple[int, bool]:
        """(0-based line, found at or after ``start``)."""
        key, lines = _norm(rendered), self.norm
        if not key:  # nothing but markers, e.g. a leaked ```
            key, lines = " ".join(rendered.split()), self.raw
        n = len(lines)
        code_ok = rendered.lstrip().startswith(CODE_LIKE)
        if key:
            for i in [*range(start, n), *range(0, min(start, n))]:
                if key in lines[i] and (code_ok or not self.scan.in_code[i]):
                    return i, i >= start
        if not n:
            return 0, False
        best = max(range(n), key=lambda i: (difflib.SequenceMatcher(None, key, lines[i]).ratio(), -i))
        return best, False

    def line(self, rendered: str, start: int = 0) -> int:
        """The 1-based line number of :meth:`find`."""
        return self.find(rendered, start)[0] + 1


@dataclass
class RenderedTable:
    columns: int
    rows: int


def check_markdown(text: str, name: str) -> list[Problem]:
    """Every rendering problem of one Markdown page, ``name`` used in the reports."""
    scan = scan_source(text)
    found: set[tuple[int, str]] = set(scan.problems)
    locator = _Locator(scan)
    hint = 0
    tree = parse_html(render(text))

    tables: list[RenderedTable] = []
    for node in tree.walk():
        if node.tag == "table":
            head = [n for n in node.walk() if n.tag == "th"]
            body = [n for n in node.walk() if n.tag == "tr" and not any(c.tag == "th" for c in n.walk())]
            tables.append(RenderedTable(len(head), len(body)))
        if node.tag not in BLOCKS:
            continue
        shown, masked = inline_text(node)
        first = next((line for line in shown.split("\n") if line.strip()), "")
        if not first:
            continue
        at, forward = locator.find(first, hint)
        if forward:
            hint = at

        locate = functools.partial(locator.line, start=at)
        if node.tag in HEADINGS and shown.strip().startswith(CODE_LIKE):
            kind = "a table row" if shown.strip().startswith("|") else "a code fence"
            found.add((locate(shown.strip()), f"<{node.tag}> whose text is really {kind}: "
                                              f"{shown.strip()[:60]!r}"))
            continue
        if node.tag in ("td", "th"):
            for code in (n for n in node.walk() if n.tag == "code"):
                code_text = "".join(c for c in code.children if isinstance(c, str))
                if "\\|" in code_text:
                    found.add((locate(code_text), f"'\\|' shows with its backslash in the code {code_text!r} "
                                                  f"of a table cell (inside backticks a '|' needs no escape)"))
        shown_lines = shown.split("\n")
        for pattern, message in LEAKS:
            for k, line in enumerate(masked.split("\n")):
                if pattern.search(line):
                    found.add((locate(shown_lines[k]), f"{message}: {shown_lines[k].strip()[:70]!r}"))
                    break  # one report per element and kind

    # source tables that look right must have become rendered tables of the same shape
    reported = {line for line, _ in found}
    k = 0
    for block in scan.tables:
        if len(block) < 2 or is_separator(block[0][1]) or not is_separator(block[1][1]):
            continue  # already reported by the source scan
        want = RenderedTable(len(table_cells(block[0][1])), len(block) - 2)
        j = next((j for j in range(k, len(tables)) if tables[j] == want), None)
        if j is None:
            if not any(n in reported for n, _ in block):
                found.add((block[0][0], f"these {len(block)} lines starting with '|' did not render as a "
                                        f"{want.columns}-column table of {want.rows} rows"))
        else:
            k = j + 1
    return sorted(Problem(name, line, message) for line, message in found)


def check_page(path: Path) -> list[Problem]:
    try:
        name = path.relative_to(ROOT).as_posix()
    except ValueError:
        name = str(path)
    return check_markdown(path.read_text(encoding="utf-8-sig"), name)


# --------------------------------------------------------------------------- the pages
def test_renderer_uses_the_mkdocs_settings():
    names, settings = markdown_settings()
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=_TolerantLoader)
    for item in config["markdown_extensions"]:
        assert (item if isinstance(item, str) else next(iter(item))) in names
    assert "fenced_code" in names  # MkDocs adds it to every build
    html = render("# T\n\n$x$ and\n\n```python\na | b\n```\n\n| a |\n| - |\n| 1 |\n")
    assert "headerlink" in html and "<table>" in html and "<pre><code" in html
    assert '<span class="arithmatex">' in html  # pymdownx.arithmatex, generic


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(DOCS).as_posix() for p in PAGES])
def test_page_renders_as_written(page):
    problems = check_page(page)
    assert not problems, "\n" + "\n".join(map(str, problems))


# --------------------------------------------------------------------------- the checker itself
#: fixture page -> (line, words of the message) that the checker must report.
BROKEN_EXPECTED = {
    # the defect of docs/cli.md: a stray '#' turned the header row into a heading
    "table_in_heading.md": [(5, "heading whose text is really a table row"),
                            (5, "<h1> whose text is really a table row"),
                            (6, "table starts with its separator row"),
                            (6, "a table row shows as text"),
                            (6, "table separator row (|---|) shows as text")],
    # the defect of docs/api.md: a stray '#' turned the opening fence into a heading
    "fence_in_heading.md": [(3, "heading whose text is really a code fence"),
                            (3, "<h1> whose text is really a code fence"),
                            (8, "code fence ``` is never closed"),
                            (8, "a code fence shows as text")],
    "broken_table.md": [(7, "table row has 3 cells, its header 2"),
                        (8, "table row has 4 cells, its header 2"),
                        (11, "a table row shows as text"),
                        (12, "table separator row (|---|) shows as text"),
                        (17, "a table row shows as text"),
                        (17, "without a separator row"),
                        (24, "shows with its backslash")],
    "unclosed_fence.md": [(5, "code fence ~~~ is never closed"),
                          (5, "a code fence shows as text")],
    "leaked_syntax.md": [(4, "'!!!' shows as text"),
                         (7, "link syntax"),
                         (9, "emphasis markers"),
                         (12, "heading marker")],
}


@pytest.mark.parametrize("name", sorted(BROKEN_EXPECTED))
def test_checker_reports_each_defect(name):
    problems = check_page(BROKEN / name)
    text = "\n".join(map(str, problems))
    for line, words in BROKEN_EXPECTED[name]:
        assert any(p.line == line and words in p.message for p in problems), \
            f"expected line {line}: {words!r} among\n{text}"
    # nothing else: every report is one of the expected ones
    assert all(any(p.line == line and words in p.message for line, words in BROKEN_EXPECTED[name])
               for p in problems), text


def test_checker_is_quiet_on_a_clean_page():
    """Tables with code, escaped pipes and math, fences of both kinds (one holding '|' rows
    and '#' lines), display math, an admonition and headings: nothing to report."""
    assert check_page(BROKEN / "clean.md") == []


def test_fixtures_are_all_checked():
    assert sorted(p.name for p in BROKEN.glob("*.md")) == sorted([*BROKEN_EXPECTED, "clean.md"])


# --------------------------------------------------------------------------- cli.md covers the parser
def _sections(text: str) -> dict[str, str]:
    """Heading text -> the text under it, up to the next heading of any level (fenced code
    is not searched for headings)."""
    out: dict[str, str] = {}
    title, body, in_fence = "", [], False
    for line in text.splitlines():
        if FENCE.match(line):
            in_fence = not in_fence
        h = None if in_fence else ATX.match(line)
        if h:
            out[title] = "\n".join(body)
            title, body = h[2].strip(), []
        else:
            body.append(line)
    out[title] = "\n".join(body)
    return out


def _long_options(parser: argparse.ArgumentParser) -> list[str]:
    return [s for a in parser._actions if not isinstance(a, argparse._HelpAction)
            for s in a.option_strings if s.startswith("--")]


def _mentions(text: str, option: str) -> bool:
    return re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", text) is not None


def cli_reference_gaps(text: str) -> list[str]:
    """``subcommand --option`` for every subcommand and option of the parser that docs/cli.md
    does not document: each subcommand has a section headed by ``prs-geom <name>`` that names
    every one of its long options; the top-level options are named anywhere on the page."""
    from prs_geom.cli import make_parser

    parser = make_parser()
    sections = _sections(text)
    missing = [f"prs-geom {o}" for o in _long_options(parser) if not _mentions(text, o)]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, subparser in sub.choices.items():
        heads = [t for t in sections if re.search(rf"prs-geom {re.escape(name)}(?![\w-])", t)]
        if not heads:
            missing.append(f"{name} (no section headed `prs-geom {name}`)")
            missing += [f"{name} {o}" for o in _long_options(subparser)]
            continue
        body = "\n".join(sections[t] for t in heads)
        missing += [f"{name} {o}" for o in _long_options(subparser) if not _mentions(body, o)]
    return missing


def test_cli_reference_covers_every_option():
    missing = cli_reference_gaps((DOCS / "cli.md").read_text(encoding="utf-8"))
    assert not missing, "docs/cli.md does not document:\n" + "\n".join(missing)


def test_cli_reference_gaps_are_found():
    """The coverage check itself: a page without the sweep section and without --json."""
    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    cut = re.sub(r"--json", "--jsn", text)
    missing = cli_reference_gaps(cut)
    assert {"contact --json", "check --json", "sweep --json", "harmonic --json"} <= set(missing)
    no_sweep = re.sub(r"prs-geom sweep", "prs-geom swept", text)
    assert any(m.startswith("sweep (no section") for m in cli_reference_gaps(no_sweep))


# --------------------------------------------------------------------------- index.md lists the theory
def test_index_links_every_theory_page():
    html = render((DOCS / "index.md").read_text(encoding="utf-8"))
    linked = {a.attrs.get("href", "").split("#")[0] for a in parse_html(html).walk() if a.tag == "a"}
    missing = [p.relative_to(DOCS).as_posix() for p in sorted((DOCS / "theory").glob("*.md"))
               if p.relative_to(DOCS).as_posix() not in linked]
    assert not missing, "docs/index.md does not link: " + ", ".join(missing)


def test_api_reference_covers_every_module():
    """Each public module of the package has its ``::: module`` entry on one page of docs/
    (the API reference, or the topic page that explains it; mkdocstrings renders the names
    of its ``__all__``); private modules (``_name``) and ``__main__`` are not API."""
    package = ROOT / "prs_geom"
    modules = set()
    for path in package.rglob("*.py"):
        parts = path.relative_to(ROOT).with_suffix("").parts
        parts = parts[:-1] if parts[-1] == "__init__" else parts
        if not any(p.startswith("_") for p in parts):
            modules.add(".".join(parts))
    documented = {m for page in PAGES
                  for m in re.findall(r"^::: (\S+)", page.read_text(encoding="utf-8"), re.M)}
    assert sorted(modules - documented) == [], "modules without a reference entry"
    assert sorted(documented - modules) == [], "reference entries of modules that do not exist"
