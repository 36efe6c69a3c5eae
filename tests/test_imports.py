"""Imports flow one way (issue 15): no two of the project's modules import each other, even
through others or from inside a function, and the lower layers import nothing above them.
``scripts/import_graph.py`` prints the graph's cycles and function-level imports."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "import_graph.py"


@pytest.fixture(scope="module")
def graph():
    spec = importlib.util.spec_from_file_location("import_graph", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up)
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


@pytest.fixture(scope="module")
def imports(graph):
    return graph.all_imports()


def test_no_module_imports_itself_through_others(graph, imports) -> None:
    assert graph.cycles(imports) == []


def test_a_cycle_is_found_through_a_function_level_import(graph) -> None:
    first = graph.Import("a", "b", 1, is_in_function=False)
    back = graph.Import("b", "c", 2, is_in_function=False)
    lazy = graph.Import("c", "a", 3, is_in_function=True)
    assert graph.cycles([first, back, lazy]) == [["a", "b", "c"]]
    assert graph.cycles([first, back]) == []


def test_nml_imports_only_nml(imports) -> None:
    # the message layer is below every process: it may not know them
    outside = [i for i in imports if i.source.startswith("nml") and not i.target.startswith("nml")]
    assert outside == []


def test_hal_components_import_nothing_of_motion(imports) -> None:
    # kinematics are motion's modules, found by name by the realtime host (hal/rtapi_app.py)
    found = [
        i
        for i in imports
        if i.source.startswith("hal.components") and i.target.split(".")[0] == "motion"
    ]
    assert found == []


def test_the_check_sees_imports_inside_functions(imports) -> None:
    # (the graph is not empty of the kind of import the cycles above were made of)
    assert any(i.is_in_function for i in imports)
