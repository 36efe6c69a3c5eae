#!/usr/bin/env python3
"""The project's import graph: which modules import which, and where imports do not flow
one way.

Prints (or returns, for tests/test_imports.py) two lists:

- **cycles**: groups of the project's modules that import each other, directly or through
  others, counting imports inside functions too (a function-level import that breaks a
  cycle at start-up still ties the two modules together);
- **function-level imports** of the project's own modules, each with file and line: most
  are a cycle's workaround, the others (a heavy or optional part loaded on first use) say
  so in ``LAZY_BY_DESIGN``.

Imports under ``if TYPE_CHECKING:`` are for type checkers only and are not counted.

    python3 scripts/import_graph.py          # both lists; exit status 1 when there is a cycle
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PACKAGES = ("cnc", "nml", "motion", "task", "iocontrol", "hal")


@dataclass(frozen=True)
class Import:
    source: str  # the importing module
    target: str  # the imported project module
    line: int
    is_in_function: bool


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def project_modules() -> dict[str, Path]:
    modules = {}
    for package in PACKAGES:
        for path in sorted((REPO / package).rglob("*.py")):
            modules[module_name(path)] = path
    return modules


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> list[Import]:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: list[Import] = []

    def target_of(dotted: str) -> str | None:
        # the deepest project module the dotted name reaches
        while dotted and dotted not in modules:
            dotted = dotted.rpartition(".")[0]
        return dotted or None

    def visit(node: ast.AST, is_in_function: bool) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child, is_in_function)
            return
        if isinstance(node, ast.Import):
            for alias in node.names:
                target = target_of(alias.name)
                if target:
                    found.append(Import(name, target, node.lineno, is_in_function))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                target = target_of(f"{base}.{alias.name}") or target_of(base)
                if target:
                    found.append(Import(name, target, node.lineno, is_in_function))
        is_function = isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
        for child in ast.iter_child_nodes(node):
            visit(child, is_in_function or is_function)

    visit(tree, False)
    return [i for i in found if i.target != name]


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def all_imports() -> list[Import]:
    modules = project_modules()
    return [i for name, path in modules.items() for i in imports_of(name, path, modules)]


def cycles(imports: list[Import]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm)."""
    graph: dict[str, set[str]] = {}
    for i in imports:
        graph.setdefault(i.source, set()).add(i.target)
        graph.setdefault(i.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def connect(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in sorted(graph[node]):
            if other not in index:
                connect(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for node in sorted(graph):
        if node not in index:
            connect(node)
    return sorted(groups)


def main() -> int:
    imports = all_imports()
    found = cycles(imports)
    for group in found:
        print("cycle:", " <-> ".join(group))
        for i in imports:
            if i.source in group and i.target in group:
                where = "in a function" if i.is_in_function else "at module level"
                print(f"    {i.source}:{i.line} imports {i.target} {where}")
    for i in imports:
        if i.is_in_function:
            print(f"function-level: {i.source}:{i.line} imports {i.target}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
