"""The process models keep one protocol (process.protocol) and nothing outside
``process/`` asks which model it has (issue 41): no ``isinstance`` on a model class,
no comparison with a model's name; the cell's ``process:`` schema has one section per
registered model."""

import ast
import dataclasses
import inspect
import typing
from pathlib import Path

import numpy as np
import pytest

from offline_prog.config.process_keys import ProcessConfig
from offline_prog.io_events import ProcessIo
from offline_prog.process.protocol import ProcessModel
from offline_prog.process.registry import MODELS, process_model

PACKAGE = Path(__file__).resolve().parents[2] / "offline_prog"
CLASSES = {model.__name__ for model in MODELS.values()}


def test_every_model_keeps_the_protocol_and_has_its_section():
    hints = typing.get_type_hints(ProcessConfig)
    assert set(hints) == {"model", *MODELS}
    columns = set()
    for name, model in MODELS.items():
        assert issubclass(model, ProcessModel) and not inspect.isabstract(model), name
        assert model.name == name and dataclasses.is_dataclass(model.Keys)
        assert hints[name] == model.Keys | None  # process.<name>: the model's own keys
        columns.add(model.column)
    assert len(columns) == len(MODELS)  # one trajectory.csv column per model


def _asks_which_model(tree: ast.AST) -> list[int]:
    """Lines that test a model's class (isinstance) or compare with a model's name."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance":
            classes = node.args[1]
            names = {n.id for n in ast.walk(classes) if isinstance(n, ast.Name)}
            names |= {n.attr for n in ast.walk(classes) if isinstance(n, ast.Attribute)}
            if names & CLASSES:
                lines.append(node.lineno)
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            if any(isinstance(x, ast.Constant) and x.value in MODELS for x in operands):
                lines.append(node.lineno)
    return lines


def test_nothing_outside_process_asks_which_model_it_has():
    found = {}
    for file in PACKAGE.rglob("*.py"):
        if "process" in file.relative_to(PACKAGE).parts[:1]:
            continue
        lines = _asks_which_model(ast.parse(file.read_text(encoding="utf-8")))
        if lines:
            found[str(file.relative_to(PACKAGE))] = lines
    assert not found, f"asks which process model it has: {found}"


def test_the_scan_sees_each_form():
    """The check above fails where code asks (a check that cannot fail proves nothing)."""
    asks = [
        "isinstance(model, BeadModel)",
        "isinstance(m, (HeatInputModel, TapeHeatingModel))",
        "isinstance(m, bead.BeadModel)",
        'process.model == "bead"',
        '"tape_heating" != cell.process.model',
    ]
    for text in asks:
        assert _asks_which_model(ast.parse(text)) == [1], text
    assert _asks_which_model(ast.parse("isinstance(x, float); y == 'flow'")) == []


@pytest.mark.parametrize("name", list(MODELS))
def test_a_steady_speed_in_the_band_is_in_the_band(name):
    """Through the protocol alone: at a steady speed in the middle of the model's speed
    band, the quality lies within its band on every row, and where the output follows
    the speed (the bead's flow, the heater's power) it is the target itself."""
    from process.test_quality import BEAD, TAPE, WELD  # the demo cells' keys

    process = {"bead": BEAD, "heat_input": WELD, "tape_heating": TAPE}[name]
    model = process_model(process)
    flow = {"analog_output": 1, "min": 0.0, "max": 10.0}  # the cell's flow output
    fields = (flow if model.sets_flow else {}) | model.speed_output()
    settings = ProcessIo(**fields) if fields else None
    low, high = model.speed_band(*((settings.min, settings.max) if settings else (0.0, 0.0)))
    v = np.full(2000, 0.5 * (low + high))
    t = np.arange(len(v)) * 1e-3
    command = None if settings is None else settings.flow(v)
    values = model.predict(t, v, command)
    assert np.all(model.delivered(t, command) > 0)
    assert not model.saturated(v, settings).any()
    assert np.all((values >= model.band[0]) & (values <= model.band[1]))
    if settings is not None:
        np.testing.assert_allclose(values, model.target, rtol=1e-9)
