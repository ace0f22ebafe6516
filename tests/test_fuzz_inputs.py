"""Seeded fuzzing of the inputs: cell YAML, path CSV, flags, plan folders.

Whatever the input, the command ends with exit 0, 1 or 2 and at most one line on
stderr, never exit 3 (a bug of ours) or a traceback. The fast variant checks the input
stage (the cell, its checks, the path points, the robot) the way the CLI maps errors;
the slow variant runs whole ``offline-prog plan`` commands in-process.
"""

import argparse
import codecs
import shutil

import numpy as np
import pytest
from config.test_cell_errors import BASE, CSV  # tests/config, as a namespace package

from offline_prog.cli import exit_code, main
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import load_inputs

HOSTILE_VALUES = [
    ".nan",
    ".inf",
    "-.inf",
    "-1",
    "0",
    "1e308",
    "1.0e+6",
    "1e6",
    "100",
    "''",
    "[]",
    "{}",
    "[1, 2, 3, 4]",
    "!Rpy {deg: [0, 0, 0]}",
    "*undefined",
    "&a [*a]",
    '"x\\ny"',
    '"\\u2028;%\\""',
    "yes",
    "null",
    "~",
    "0x10",
    "'\\x00'",
    "[[[[[[[[[[]]]]]]]]]]",
    "é",
    "9" * 400,
    "-0.0",
    "2.5e-320",
]


def mutate_yaml(rng, text: str) -> bytes:
    """One random mutation of a cell file (as bytes: encodings are mutated too)."""
    lines = text.splitlines()
    kind = rng.integers(10)
    k = int(rng.integers(len(lines)))
    if kind == 0:  # replace a value
        key = lines[k].split(":")[0]
        lines[k] = f"{key}: {HOSTILE_VALUES[rng.integers(len(HOSTILE_VALUES))]}"
    elif kind == 1:
        del lines[k]
    elif kind == 2:
        lines.insert(k, lines[int(rng.integers(len(lines)))])
    elif kind == 3:  # indentation
        lines[k] = " " * int(rng.integers(0, 5)) + lines[k].lstrip()
    elif kind == 4:  # truncation
        return text.encode()[: int(rng.integers(len(text)))]
    elif kind == 5:  # flipped bytes
        data = bytearray(text.encode())
        for i in rng.integers(len(data), size=3):
            data[i] = int(rng.integers(256))
        return bytes(data)
    elif kind == 6:
        return text.replace("name: test", "name: Düse").encode("latin-1")
    elif kind == 7:
        return codecs.BOM_UTF8 + text.encode()
    elif kind == 8:  # an alias bomb or deep nesting under a key
        bomb = "lol: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
            f"l{i}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(7)
        )
        return (text + (bomb if rng.random() < 0.5 else "deep: " + "[" * 5000)).encode()
    else:  # a string with line breaks and quotes in the name
        lines[0] = 'name: "x\\nsocket_open(\\"h\\", 1)\\r;%"'
    return ("\n".join(lines) + "\n").encode()


def mutate_csv(rng, text: str) -> bytes:
    lines = text.splitlines()
    kind = rng.integers(5)
    k = int(rng.integers(1, len(lines)))
    if kind == 0:
        lines[k] = ",".join(rng.choice(["nan", "inf", "1e400", "x", "", "-0"], size=3))
    elif kind == 1:
        lines = lines[: int(rng.integers(1, len(lines)))]
    elif kind == 2:
        lines[k] = lines[k] + ",1"
    elif kind == 3:
        return text.encode("utf-16")
    else:
        lines = [lines[0]] + [lines[1]] * (len(lines) - 1)
    return ("\n".join(lines) + "\n").encode()


def assert_one_line_no_bug(error: BaseException, command: str = "plan") -> None:
    args = argparse.Namespace(command=command, out=None, cell="cell.yaml", plan_dir="plan")
    code, message = exit_code(error, args)
    assert code in (1, 2), f"{code}: {message}"
    assert "\n" not in message and "Traceback" not in message


def input_stage(cell) -> None:
    """The input stage as the CLI runs it: errors mapped to one line, exit 1 or 2."""
    try:
        load_inputs(cell, ROBOTS_DIR)
    except Exception as error:  # noqa: BLE001 - every error is checked, not swallowed
        assert_one_line_no_bug(error)


def write_case(tmp_path, cell_bytes: bytes, csv_bytes: bytes | None = None):
    (tmp_path / "path.csv").write_bytes(CSV.encode() if csv_bytes is None else csv_bytes)
    cell = tmp_path / "cell.yaml"
    cell.write_bytes(cell_bytes)
    return cell


@pytest.mark.parametrize("seed", range(60))
def test_fuzzed_cell_files_fast(tmp_path, seed):
    rng = np.random.default_rng(seed)
    input_stage(write_case(tmp_path, mutate_yaml(rng, BASE)))


@pytest.mark.parametrize("seed", range(20))
def test_fuzzed_path_csv_fast(tmp_path, seed):
    rng = np.random.default_rng(1000 + seed)
    input_stage(write_case(tmp_path, BASE.encode(), mutate_csv(rng, CSV)))


FLAG_VALUES = ["nan", "inf", "-inf", "-1", "0", "1e999", "x", "", "0x10", "1e-320", "3.5", "٣"]


@pytest.mark.parametrize("seed", range(20))
def test_fuzzed_export_flags_fast(capsys, tmp_path, seed):
    rng = np.random.default_rng(2000 + seed)
    flags = ["--chord-tol-mm", "--angle-tol-deg", "--line-limit"]
    argv = ["export", str(tmp_path), "--format", "krl"]
    for flag in rng.choice(flags, size=int(rng.integers(1, 4)), replace=False):
        argv += [flag, str(rng.choice(FLAG_VALUES))]
    try:
        code = main(argv)
    except SystemExit as exit:
        code = exit.code
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, (argv, err)  # bad flag, or no plan in tmp_path


@pytest.mark.parametrize("seed", range(10))
def test_damaged_plan_folders_fast(capsys, planned_folder, tmp_path, seed):
    rng = np.random.default_rng(3000 + seed)
    folder = tmp_path / "plan"
    shutil.copytree(planned_folder("seal_plate_kr16")[1], folder)
    npz = folder / "plan.npz"
    data = bytearray(npz.read_bytes())
    if seed % 2:
        data = data[: int(rng.integers(len(data)))]
    else:
        for i in rng.integers(len(data), size=20):
            data[i] = int(rng.integers(256))
    npz.write_bytes(bytes(data))
    code = main(["export", str(folder), "--format", "csv", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.splitlines()
    assert code in (0, 2) and len(err) <= 1, err


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_fuzzed_cells_whole_command_slow(capsys, tmp_path, seed):
    rng = np.random.default_rng(4000 + seed)
    csv = mutate_csv(rng, CSV) if seed % 4 == 3 else None
    cell = write_case(tmp_path, mutate_yaml(rng, BASE), csv)
    code = main(["plan", str(cell), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.splitlines()
    assert code in (0, 1, 2) and len(err) <= 1, err
    if code == 2:
        assert not (tmp_path / "out").exists()  # nothing half-written
