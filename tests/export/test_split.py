"""``line_limit``: a KRL and a RAPID job split into called parts at a small limit, read
back part by part, run as the unsplit program does (the FANUC split:
tests/robot_import/test_fanuc_job)."""

import re

import numpy as np
import pytest

from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.split import MIN_LINE_LIMIT, split_blocks

from conftest import CELLS, planned_text, with_own_io
from rapid_reader import rapid_procs

IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 2, lead_mm: 3}\n"
    "    off: {digital_output: 2, lead_mm: 4}\n"
    "    flow: {analog_output: 1, per_mps: 30.0, offset: 1.0, min: 0.0, max: 10.0}\n"
)


def test_parts_cover_every_block_in_order_within_the_limit():
    rng = np.random.default_rng(0)
    for _ in range(300):
        n, limit = int(rng.integers(1, 60)), int(rng.integers(MIN_LINE_LIMIT, 60))
        sizes = rng.integers(1, 5, n).tolist()
        opening = rng.integers(0, 2, n).tolist()
        parts = split_blocks(sizes, limit, frame=2, opening=opening)
        assert [k for part in parts for k in part] == list(range(n))
        for part in parts:
            used = 2 + opening[part.start] + sum(sizes[k] for k in part)
            assert used <= limit
        # greedy: the next part's first block would not have fitted
        for a, b in zip(parts, parts[1:], strict=False):
            assert 2 + opening[a.start] + sum(sizes[k] for k in a) + sizes[b.start] > limit
    assert split_blocks([3, 3], None, frame=2) == [range(2)]
    with pytest.raises(ValueError, match="line_limit=20"):
        split_blocks([30], 20, frame=2)


# --- KRL --------------------------------------------------------------------------------

KRL_DECL = re.compile(r"^DECL (E6POS|E6AXIS) (\w+)=\{(.*)\}$")


def krl_lins(folder, name="offline_prog"):
    """Every motion of the job as run, following the calls into the seams' modules and
    their parts: (statement, its target's values, $VEL.CP, the TRIGGERs before it).
    Also the lines (DEF to END) of each seam module."""
    out, state, lengths = [], {"vel": None, "triggers": []}, {}

    def read(module):
        decls = {
            m[2]: m[3]
            for line in (folder / f"{module}.dat").read_text().splitlines()
            if (m := KRL_DECL.match(line))
        }
        main = {
            m[2]: m[3]
            for line in (folder / f"{name}.dat").read_text().splitlines()
            if (m := KRL_DECL.match(line))
        }
        body = [line for line in (folder / f"{module}.src").read_text().splitlines()]
        body = [line for line in body if line and not line.startswith(";")]
        lengths[module] = len(body)
        for line in body:
            if re.fullmatch(rf"{name}_\d+(_\d+)?\( \)", line):
                read(line.split("(")[0])
            elif line.startswith("$VEL.CP="):
                state["vel"] = float(line.split("=")[1])
            elif line.startswith("TRIGGER"):
                state["triggers"].append(line)
            elif m := re.match(r"(LIN|PTP) (\w+)( C_DIS)?$", line):
                target = decls.get(m[2], main.get(m[2]))
                out.append((m[1] + (m[3] or ""), target, state["vel"], tuple(state["triggers"])))
                state["triggers"] = []

    read(name)
    return out, lengths


def test_krl_job_split_at_a_small_limit_runs_as_the_unsplit_one(planned_job, tmp_path):
    data = JobProgramData.load(planned_job("seal_job_kr16")[1])
    export(data, "krl", tmp_path / "whole")
    limit = 110  # the main program of the demo job needs about 70 lines with its calls
    export(data, "krl", tmp_path / "split", line_limit=limit)
    whole, whole_lengths = krl_lins(tmp_path / "whole")
    split, split_lengths = krl_lins(tmp_path / "split")
    assert len(split_lengths) > len(whole_lengths) + 2  # the seams run as several parts
    assert max(whole_lengths.values()) > limit
    assert max(split_lengths.values()) <= limit
    assert split == whole
    assert sum(bool(triggers) for *_, triggers in split) >= 2 * len(data.seam_names)


# --- RAPID ------------------------------------------------------------------------------


def rapid_statements(module_text: str) -> tuple[list[str], dict[str, int]]:
    """The main routine's statements with every called routine's in its place, and the
    lines (PROC to ENDPROC) of each routine."""
    procs = rapid_procs(module_text)
    run = []
    for line in procs["main"]:
        call = line.split(";")[0]
        run += procs.get(call, [line])
    return run, {name: len(body) + 2 for name, body in procs.items()}


def check_rapid_split(data: JobProgramData, folder, limit: int) -> list[str]:
    """Export the job whole and split at ``limit``: the same statements run, each routine
    within the limit, the same data declared. Returns the statements run."""
    (whole_mod, *_) = export(data, "rapid", folder / "whole")
    (split_mod, *_) = export(data, "rapid", folder / "split", line_limit=limit)
    whole, whole_lengths = rapid_statements(whole_mod.read_text())
    split, split_lengths = rapid_statements(split_mod.read_text())
    assert max(whole_lengths.values()) > limit
    assert max(split_lengths.values()) <= limit and len(split_lengths) > len(whole_lengths)
    assert split == whole  # the same moves, targets, speeds, zones and triggers in order
    decl = re.compile(r"^\s*(?:LOCAL CONST|VAR|PERS) .*;$", re.M)
    assert sorted(decl.findall(split_mod.read_text())) == sorted(
        decl.findall(whole_mod.read_text())
    )
    return split


def test_rapid_job_split_at_a_small_limit_runs_as_the_unsplit_one(planned_job, tmp_path):
    check_rapid_split(JobProgramData.load(planned_job("weld_seam_irb2400")[1]), tmp_path, 30)


@pytest.mark.slow  # plans a job of its own
def test_rapid_job_with_io_split_switches_as_the_unsplit_one(tmp_path):
    text = with_own_io((CELLS / "weld_seam_irb2400.yaml").read_text(), IO)
    _, data = planned_text(text, tmp_path)
    run = check_rapid_split(data, tmp_path, 30)
    assert sum(line.startswith("TriggIO") for line in run) == 2
    assert sum(line.startswith("TriggSpeed") for line in run) == 2


@pytest.mark.parametrize(
    ("fmt", "cell"), [("krl", "seal_job_kr16"), ("rapid", "weld_seam_irb2400")]
)
def test_a_limit_below_the_smallest_part_is_refused(planned_job, tmp_path, fmt, cell):
    data = JobProgramData.load(planned_job(cell)[1])
    with pytest.raises(ValueError, match=f"line_limit={MIN_LINE_LIMIT - 1}: need a whole number"):
        export(data, fmt, tmp_path, line_limit=MIN_LINE_LIMIT - 1)
    if fmt == "krl":  # the demo job's main program: about 70 lines
        with pytest.raises(ValueError, match="the main program alone needs"):
            export(data, fmt, tmp_path, line_limit=MIN_LINE_LIMIT)
    assert not list(tmp_path.glob("*.src")) and not list(tmp_path.glob("*.mod"))
