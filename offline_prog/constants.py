"""Tolerances and defaults, named once (see toppra's constants.py)."""

import enum

import numpy as np

# B-spline fit (paper §2).
DEFAULT_SPLINE_DEGREE = 5
MIN_SPLINE_DEGREE = 5
DEFAULT_FIT_TOLERANCE_M = 1e-4  # max distance from a given point to the curve [m]
# A closed contour's points may stop short of their start by up to this many times the
# larger of the first and last point spacing (path/closing.py); more is a missing stretch.
CLOSING_GAP_STEP_RATIO = 2.0

# Arc-length re-parameterization: Newton on s(u) stops below this [m].
ARC_LENGTH_TOLERANCE_M = 1e-12

# Process frames (paper §3.1): a normal closer than this to the tangent is rejected.
MIN_NORMAL_TANGENT_ANGLE_RAD = np.deg2rad(5.0)

# Workspace trajectory.
DEFAULT_SAMPLE_RATE_HZ = 250.0

# Cusps (paper §4): flange speed per unit TCP speed |dp_IE/ds| below this is a cusp,
# and a local peak above CUSP_PEAK_RATIO times the path median is a speed peak.
CUSP_MIN_FLANGE_RATIO = 0.05
CUSP_PEAK_RATIO = 3.0

# Length units a cell file may use, in metres per unit.
UNIT_SCALE = {"m": 1.0, "mm": 1e-3}

# Below this TCP speed the tool stands: a bead's cross-section, a weld's heat input and
# a tape's nip temperature (per metre of path) are not defined there [m/s].
STANDSTILL_SPEED_M_S = 1e-4

# Input limits: no hang and no runaway memory on a hostile or mistaken input. Each is
# named here once; the message that enforces it quotes it.
MAX_CELL_FILE_BYTES = 1_000_000  # a cell file is a few kB; larger is not a cell file
MAX_DATA_FILE_BYTES = 200_000_000  # path CSV / DXF and meshes
MAX_YAML_NODES = 100_000  # values in a cell file, aliases expanded (alias bombs)
MAX_YAML_DEPTH = 50  # nesting of a cell file's lists and mappings
MAX_SAMPLES = 2_000_000  # trajectory samples of one plan (duration x sample rate)
MAX_SAMPLE_RATE_HZ = 10_000.0  # controllers interpolate at 0.25-4 kHz
LIMIT_CHECK_RATE_HZ = 1000.0  # joint speed/acceleration checked at this rate
MAX_SPEED_M_S = 2.0  # motion.speed: process speeds are mm/s to ~1 m/s; above is a unit slip
MAX_VALUE_CHARS = 80  # a value quoted in an error message is cut to this
MAX_PAYLOAD_KG = 1000.0  # gripper.mass_kg, part.mass_kg: beyond any arm this package drives
MAX_CENTER_OF_MASS_MM = 5000.0  # |center_of_mass_mm| from its frame's origin
# place.budget / --budget: candidates planned in full; 10⁵ × ~2 s is days on one core.
MAX_PLACE_BUDGET = 100_000
# place.seed / --seed: seeds the shift of the placement search's grid (numpy takes seeds
# below 2³²; the bound is the one the search has always had).
MAX_PLACE_SEED = 2**31 - 1
# A work cell is smaller than this across: a mesh larger, or a pose farther from its
# frame's origin, is a unit slip (mm read as m: 1000×; config.unit_slips).
MAX_CELL_EXTENT_M = 20.0


class TimeLaw(enum.StrEnum):
    """motion.time_law: TOPP-RA + jerk stage (the default, config/cell.py), or the paper's
    sin² law. The values are the cell file's strings (the contract); report.json and the
    program headers write them unchanged (a StrEnum is its value)."""

    TIME_OPTIMAL = "time_optimal"
    SIN2 = "sin2"


class ProcessIntent(enum.StrEnum):
    """motion.process, the time-optimal law's intent: hold the process speed wherever the
    robot can (sealing, gluing), or anything up to it for the shortest cycle."""

    CONSTANT_SPEED = "constant_speed"
    CYCLE_TIME = "cycle_time"


TIME_LAWS = tuple(law.value for law in TimeLaw)
PROCESS_INTENTS = tuple(intent.value for intent in ProcessIntent)
# The flow output goes live this many of its lags (flow.lag_s, a bead's lag_s) before
# the valve opens: a first-order lag is then within e^-4 = 1.8 % of its command when
# the bead starts (one lag ahead left it 37 % short, e^-1).
FLOW_PRIME_LAGS = 4.0
