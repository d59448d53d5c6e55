"""A hostile corpus of model, robot, measurement and layout files, and every command that reads them (issue 26).

`build_base` writes a valid set into a folder: the UR10's robot file, a
125-point plan, its measurements on the virtual arm, a composite model whose
grid lives in a sidecar ``.npz``, a layout file and a program CSV. `cases`
turns each of those files into hostile ones, one `Case` at a time:

- the byte mutations of tests/test_fuzz.py (bit flips, truncation, blown-up
  numbers, a line x1000, leading punctuation...);
- every value of a YAML document replaced by an extreme or wrong one (1e308,
  NaN, infinity, 1e-320, a 400-digit integer, text, null, a list or mapping
  of the wrong size) or deleted;
- whole-file attacks: empty, binary junk, NUL bytes, another encoding, deep
  nesting, an alias bomb, a giant file, a key given twice, ``!!python``
  tags;
- what an operator's bad day brings: wrong units, another robot's model or
  measurements, a sidecar of another calibration, a zip bomb, an ``.npy``
  header claiming terabytes, rows repeated, columns missing.

`COMMANDS` names the commands that read each kind of file; `run` runs one
case's commands in this process and returns their exit codes and messages.
tests/test_hostile_files.py runs a sample and asserts the contract (exit 0,
1 or 2, never a crash; a refusal names the hostile file);
tests/benchmarks/bench_hostile.py runs all of it, each case in a process of
its own, and prints the time and memory of each kind.
"""

import contextlib
import copy
import dataclasses
import hashlib
import io
import math
import random
import re
import shutil
import time
import zipfile
from importlib import resources
from pathlib import Path

import numpy as np
import yaml

from test_fuzz import mutate
from trajcomp.model import model_file
from trajcomp.calibration.calibrate import calibrate
from trajcomp.cli import main
from trajcomp.calibration.measurements import Measurements, write_measurements
from trajcomp.model.model_file import save_model
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot

CUBE = ("-800,-300,400", "400", "100")  # corner, side, step (mm) of the base plan: 125 points
VALUES = (1e308, -1e308, math.nan, math.inf, 1e-320, 10**400, -0.0, "text", None, True, [], {}, [1.0] * 7)
KINDS = ("robot", "model", "measurements", "layout")
FILES = {"robot": "robot.yaml", "model": "model.yaml", "measurements": "meas.csv", "layout": "layout.yaml"}
COMMANDS = {  # {base}: the valid set, {file}: the hostile file, {out}: an empty folder for outputs
    "robot": (
        ("plan", "--robot", "{file}", f"--cube={CUBE[0]}", "--side", CUBE[1], "--step", "200", "-o", "{out}/plan.csv"),
        ("simulate", "{base}/plan.csv", "--robot", "{file}", "-o", "{out}/meas.csv"),
        ("calibrate", "{base}/meas.csv", "--robot", "{file}", "--folds", "2", "-o", "{out}/model.yaml"),
        ("retime", "{base}/program.csv", "--robot", "{file}", "-o", "{out}/program.csv"),
        ("convert", "{base}/program.csv", "{out}/program.script", "--robot", "{file}"),
    ),
    "model": (
        ("validate", "{file}", "{base}/meas.csv"),
        ("predict", "{file}", "{base}/plan.csv", "-o", "{out}/predicted.csv"),
        ("compensate", "{base}/program.csv", "--model", "{file}", "-o", "{out}/program.csv"),
        ("recalibrate", "{file}", "{base}/meas.csv", "-o", "{out}/model.yaml"),
    ),
    "measurements": (
        ("calibrate", "{file}", "--robot", "ur10", "--folds", "2", "-o", "{out}/model.yaml"),
        ("validate", "{base}/model.yaml", "{file}"),
        ("predict", "{base}/model.yaml", "{file}", "-o", "{out}/predicted.csv"),
        ("simulate", "{file}", "--robot", "ur10", "-o", "{out}/meas.csv"),
        ("recalibrate", "{base}/model.yaml", "{file}", "-o", "{out}/model.yaml"),
    ),
    "layout": (
        ("calibrate", "{base}/meas.csv", "--robot", "ur10", "--folds", "2", "--columns-file", "{file}",
         "-o", "{out}/model.yaml"),
        ("validate", "{base}/model.yaml", "{base}/meas.csv", "--columns-file", "{file}"),
        ("predict", "{base}/model.yaml", "{base}/meas.csv", "--columns-file", "{file}", "-o", "{out}/predicted.csv"),
    ),
}


@dataclasses.dataclass(frozen=True)
class Case:
    """One hostile file (and, for a model, its sidecar) of a kind of `KINDS`.

    Attributes
    ----------
    kind : str
    name : str
        What was done to the valid file, for the table and reproducers.
    files : dict
        ``{file name: bytes}`` written into the case's folder; the first is
        the file the commands read.
    refusal : str or None
        A regular expression the refusal's message must match (exit 2 is
        then the only outcome accepted); None: refused or accepted.
    by : tuple of str or None
        The commands that must refuse it (None: every command; the others
        may accept it: simulate reads no measured columns).
    """

    kind: str
    name: str
    files: dict
    refusal: str = None
    by: tuple = None


@dataclasses.dataclass(frozen=True)
class Outcome:
    """One command of a case: argv, exit code, seconds, the stderr text and the files left in the output folder."""

    argv: tuple
    code: int
    seconds: float
    message: str
    written: tuple


def build_base(folder):
    """Write the valid set into ``folder`` (about a second): robot.yaml, plan.csv, meas.csv, model.yaml and its
    sidecar model.yaml.npz, layout.yaml, program.csv."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "robot.yaml").write_bytes(resources.files("trajcomp.arm.robots").joinpath("ur10.yaml").read_bytes())
    robot = load_robot("ur10")
    corner = [float(v) for v in CUBE[0].split(",")]
    plan = plan_grid(robot, corner, float(CUBE[1]), float(CUBE[2]))
    joints, position = plan.joints[plan.reachable], plan.position[plan.reachable]
    orientation = plan.orientation[plan.reachable]
    lines = np.arange(len(joints)) + 2
    write_measurements(folder / "plan.csv", Measurements(joints=joints, position=position, orientation=orientation,
                                                         lines=lines))
    measured = VirtualRobot.create(robot, "paper", seed=1).measure(joints, np.random.default_rng(3))
    meas = Measurements(joints=joints, position=position, orientation=orientation, measured=measured, lines=lines,
                        path=str(folder / "meas.csv"))
    write_measurements(folder / "meas.csv", meas)
    model = calibrate(robot, meas, robot_ref="ur10", grid_step=float(CUBE[2]), folds=0)
    nodes = model_file._SIDECAR_NODES
    model_file._SIDECAR_NODES = 10  # the 125-node grid goes to the sidecar, as a large grid does
    try:
        save_model(folder / "model.yaml", model)
    finally:
        model_file._SIDECAR_NODES = nodes
    (folder / "layout.yaml").write_text(
        "delimiter: ','\nframe: base\ncolumns:\n" + "".join(f"  {f}: {f}\n" for f in
                                                         ("j1", "j2", "j3", "j4", "j5", "j6", "x", "y", "z", "mx"))
        + "units:\n  joints: deg\n  position: mm\n  measured: mm\nrotations:\n  orientation: ZYX\n")
    rows = np.linspace(0, len(joints) - 1, 8).astype(int)
    abc = np.degrees(orientation[rows])
    (folder / "program.csv").write_text("x,y,z,a,b,c,motion,speed\n" + "".join(
        f"{p[0]:.3f},{p[1]:.3f},{p[2]:.3f},{o[0]:.3f},{o[1]:.3f},{o[2]:.3f},LIN,250\n"
        for p, o in zip(position[rows], abc)))
    return folder


def _leaves(value, path=()):
    """Paths (tuples of keys and indices) of every value in a YAML document, containers included, the root not."""
    children = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, child in children:
        yield path + (key,)
        yield from _leaves(child, path + (key,))


def _replaced(doc, path, value):
    """A deep copy of ``doc`` with the value at ``path`` replaced by ``value`` (deleted when it is `_DELETE`)."""
    doc = copy.deepcopy(doc)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    if value is _DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return doc


_DELETE = object()


def _dump(doc):
    return yaml.safe_dump(doc, sort_keys=False, width=100, allow_unicode=True).encode("utf-8")


def _value_cases(kind, name, data, rng, count):
    """``count`` cases of a YAML file: a value at a random path replaced by one of `VALUES`, or deleted."""
    doc = yaml.safe_load(data)
    paths = list(_leaves(doc))
    for _ in range(count):
        path = rng.choice(paths)
        value = rng.choice(VALUES + (_DELETE,))
        shown = "deleted" if value is _DELETE else repr(value)[:20]
        yield Case(kind, f"{'.'.join(map(str, path))} {shown}", {name: _dump(_replaced(doc, path, value))})


def _byte_cases(kind, name, data, rng, count, extra=None):
    """``count`` cases of a file mutated by the fuzz operators of tests/test_fuzz.py (``extra``: other files kept)."""
    for _ in range(count):
        mutated, how = mutate(data, rng)
        yield Case(kind, how, {name: mutated, **(extra or {})})


def _file_attacks(kind, name, data, giant):
    """Whole-file attacks on a file of any kind; ``giant``: megabytes of the giant one (0: none)."""
    rng = random.Random(26)
    junk = bytes(rng.randrange(256) for _ in range(4096))
    yield Case(kind, "empty", {name: b""}, r".")
    yield Case(kind, "binary junk", {name: junk}, r".")
    yield Case(kind, "NUL bytes", {name: data[:200] + b"\x00" * 1000 + data[200:]}, r".")
    yield Case(kind, "UTF-16", {name: data.decode("utf-8").encode("utf-16")}, r".")
    yield Case(kind, "latin-1 bytes", {name: data + "\n# caf\xe9\n".encode("latin-1")}, r".")
    yield Case(kind, "one line of 2 MB", {name: b"9" * 2_000_000}, r".")
    if giant:
        yield Case(kind, f"{giant} MB of repeated lines", {name: data * (giant * 2**20 // len(data) + 1)})


def _yaml_attacks(kind, name, data):
    """Attacks on a YAML file: nesting, aliases, duplicate keys, tags, other document shapes."""
    head = data.decode("utf-8")
    laughs = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, "
        f"*a{i - 1}, *a{i - 1}]\n" for i in range(1, 9))
    first_key = next(iter(yaml.safe_load(data)))
    yield Case(kind, "alias bomb", {name: (laughs + head).encode()}, r"alias bomb")
    yield Case(kind, "nested 100,000 deep", {name: b"[" * 100_000 + b"]" * 100_000}, r".")
    yield Case(kind, "mappings nested 10,000 deep", {name: b"{a: " * 10_000 + b"1" + b"}" * 10_000}, r".")
    yield Case(kind, "a key given twice", {name: (head + f"\n{first_key}: again\n").encode()}, r"twice")
    yield Case(kind, "python tag", {name: b"!!python/object/apply:os.system ['echo hacked']\n" + data}, r".")
    yield Case(kind, "two documents", {name: data + b"\n---\n" + data}, r".")
    yield Case(kind, "a list", {name: b"- 1\n- 2\n"}, r".")
    yield Case(kind, "a number", {name: b"1e308\n"}, r".")
    yield Case(kind, "tabs", {name: head.replace("  ", "\t").encode()}, r".")
    yield Case(kind, "1,000,000 keys", {name: data + b"".join(b"k%d: 1\n" % i for i in range(1_000_000))})


def _sidecar_cases(base):
    """The model with hostile sidecars."""
    model = (base / "model.yaml").read_bytes()
    doc = yaml.safe_load(model)
    sidecar = (base / "model.yaml.npz").read_bytes()
    arrays = dict(np.load(io.BytesIO(sidecar)))
    key = next(iter(arrays))

    def signed(payload, **changes):  # the model naming this sidecar's SHA-256: an attack, not damage
        return {"model.yaml": _dump({**doc, "sidecar_sha256": hashlib.sha256(payload).hexdigest(), **changes}),
                "model.yaml.npz": payload}

    def npz(**members):
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **members)
        return buffer.getvalue()

    yield Case("model", "sidecar missing", {"model.yaml": model}, r"model\.yaml\.npz")
    yield Case("model", "sidecar empty", {"model.yaml": model, "model.yaml.npz": b""}, r"model\.yaml\.npz")
    yield Case("model", "sidecar truncated", {"model.yaml": model, "model.yaml.npz": sidecar[: len(sidecar) // 2]},
               r"SHA-256")
    yield Case("model", "sidecar of another calibration",
               {"model.yaml": model, "model.yaml.npz": npz(**{key: arrays[key] + 1.0})}, r"another calibration")
    for name in ("../meas.csv", "/etc/passwd", "model.yaml", ".", "a/b.npz", "x" * 5000):
        yield Case("model", f"sidecar named {name[:20]!r}", {"model.yaml": _dump({**doc, "sidecar": name})}, r".")
    yield Case("model", "sidecar of NaN", signed(npz(**{key: np.full_like(arrays[key], np.nan)})), r"not finite")
    yield Case("model", "sidecar of 1e308", signed(npz(**{key: np.full_like(arrays[key], 1e308)})))
    yield Case("model", "sidecar of text", signed(npz(**{key: np.array(["x"] * 10)})), r"not finite numbers")
    yield Case("model", "sidecar array of another shape", signed(npz(**{key: arrays[key].ravel()[:10]})))
    yield Case("model", "sidecar array 0-d", signed(npz(**{key: np.float64(1.0)})))
    yield Case("model", "sidecar without the array", signed(npz(other=arrays[key])), r".")
    yield Case("model", "sidecar holding an object array", signed(npz(**{key: np.array([{}, []], dtype=object)})),
               r".")
    yield Case("model", "sidecar a zip bomb (80 MB of zeros)", signed(npz(**{key: np.zeros(10_000_000)})), r"unpacks to")
    yield Case("model", "sidecar .npy header claiming 8 TB", signed(_npz_claiming(key, (10**12,))), r".")


def _npz_claiming(key, shape):
    """An ``.npz`` whose member ``key`` has an ``.npy`` header claiming ``shape`` float64, with 80 bytes of data."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": shape})
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr(f"{key}.npy", header.getvalue() + b"\x00" * 80)
    return buffer.getvalue()


def _model_cases(base):
    """Adversarial models: another format, another robot, another robot's reference, bad fields."""
    model = (base / "model.yaml").read_bytes()
    sidecar = {"model.yaml.npz": (base / "model.yaml.npz").read_bytes()}
    doc = yaml.safe_load(model)

    def edited(**changes):
        return {"model.yaml": _dump({**doc, **changes}), **sidecar}

    yield Case("model", "format trajcomp-model/1", edited(format="trajcomp-model/1"), r"format")
    yield Case("model", "another robot's model (ur5)", edited(robot={**doc["robot"], "name": "ur5", "ref": "ur5"}),
               r"differs from the one calibrated")
    for ref in ("/etc/passwd", "/dev/zero", "../robot.yaml", "robot.yaml", "x" * 5000):
        yield Case("model", f"robot ref {ref[:20]!r}", edited(robot={**doc["robot"], "ref": ref}), r".")
    yield Case("model", "a robot fingerprint of 1e308", edited(robot={**doc["robot"], "dh_fingerprint": [1e308] * 30}),
               r".")
    yield Case("model", "10,000 parameters", edited(parameters=doc["parameters"] * 400))
    yield Case("model", "parameter deltas of 1e308",
               edited(parameters=[{**p, "delta": 1e308} for p in doc["parameters"]]), r"parameters\.delta")
    yield Case("model", "parameter deltas of 1 m", edited(parameters=[{**p, "delta": 1000.0} for p in doc["parameters"]]),
               r"parameters\.delta")
    yield Case("model", "tracker_to_base of 1e300", edited(tracker_to_base=[1e300] * 6), r"tracker_to_base")
    yield Case("model", "grid step 0", edited(grid={**doc["grid"], "step": [0.0, 0.0, 0.0]}), r".")
    yield Case("model", "grid step -100", edited(grid={**doc["grid"], "step": [-100.0] * 3}), r".")
    yield Case("model", "grid shape of 10^9 nodes", edited(grid={**doc["grid"], "shape": [1000, 1000, 1000]}), r".")
    yield Case("model", "grid shape 4-d", edited(grid={**doc["grid"], "shape": [5, 5, 5, 5]}), r".")
    yield Case("model", "grid origin at 1e300", edited(grid={**doc["grid"], "origin": [1e300] * 3}), r".")
    yield Case("model", "grid method unknown", edited(grid={**doc["grid"], "method": "magic"}), r".")
    yield Case("model", "residual kind unknown", edited(grid={**doc["grid"], "kind": "magic"}), r".")
    yield Case("model", "linear slopes of 1e308",
               edited(linear={**doc["linear"], "dx": {**doc["linear"]["dx"], "slopes": {"x": 1e308}}}), r".")
    yield Case("model", "linear slope on axis w",
               edited(linear={**doc["linear"], "dx": {**doc["linear"]["dx"], "slopes": {"w": 1.0}}}), r".")
    yield Case("model", "method unknown", edited(method="magic"), r".")
    yield Case("model", "postures of junk", edited(postures=["up/down/left", 7]), r"postures")
    yield Case("model", "a report of 1,000,000 numbers", {  # written as text: PyYAML's emitter takes 20 s
        "model.yaml": _dump({k: v for k, v in doc.items() if k != "report"}) + b"report:\n  fit:\n" + b"  - 0\n" * 10**6,
        **sidecar})


def _robot_cases():
    """Adversarial robots: another maker's arm under the UR10's name, degenerate and absurd numbers."""
    ur10 = yaml.safe_load(resources.files("trajcomp.arm.robots").joinpath("ur10.yaml").read_bytes())
    kuka = yaml.safe_load(resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_bytes())

    def edited(name, doc, refusal=None):
        return Case("robot", name, {"robot.yaml": _dump(doc)}, refusal)

    limits = ur10["limits"]
    yield edited("a KUKA KR6 named ur10", {**kuka, "name": "ur10"})
    yield edited("every DH length 0", {**ur10, "dh": {**ur10["dh"], "a": [0] * 6, "d": [0] * 6}})
    yield edited("an arm of 10 um", {**ur10, "dh": {**ur10["dh"], "a": [0, -0.01, -0.01, 0, 0, 0],
                                                      "d": [0.01, 0, 0, 0.01, 0.01, 0.01]}})
    yield edited("lengths in metres", {**ur10, "dh": {**ur10["dh"], "a": [v / 1000 for v in ur10["dh"]["a"]],
                                                        "d": [v / 1000 for v in ur10["dh"]["d"]]}})
    yield edited("angles in radians", {**ur10, "dh": {**ur10["dh"], "alpha": [math.radians(v)
                                                                              for v in ur10["dh"]["alpha"]]}})
    yield edited("velocity 1e-300 deg/s", {**ur10, "limits": {**limits, "velocity": [1e-300] * 6}})
    yield edited("acceleration 1e-300", {**ur10, "limits": {**limits, "acceleration": [1e-300] * 6}})
    yield edited("jerk 1e-300", {**ur10, "limits": {**limits, "jerk": [1e-300] * 6}})
    yield edited("joint range +-99,999 deg", {**ur10, "limits": {**limits, "position_min": [-99999] * 6,
                                                                  "position_max": [99999] * 6}})
    yield edited("joint range of 1e-9 deg", {**ur10, "limits": {**limits, "position_min": [0] * 6,
                                                                 "position_max": [1e-9] * 6}})
    yield edited("limits swapped", {**ur10, "limits": {**limits, "position_min": limits["position_max"],
                                                       "position_max": limits["position_min"]}}, r"position_min")
    yield edited("direction 0", {**ur10, "joints": {"direction": [0] * 6}}, r"joints\.direction")
    yield edited("j3 coupling 1e5", {**ur10, "joints": {"j3_coupling": 1e5}}, r"j3_coupling: 100000 is beyond the 10")
    yield edited("convention weird", {**ur10, "dh": {**ur10["dh"], "convention": "weird"}}, r"dh\.convention")
    yield edited("home beyond the limits", {**ur10, "home": [720] * 6})
    yield edited("tool 100 m long", {**ur10, "tool": [0, 0, 99999, 0, 0, 0]})
    yield edited("seven joints", {**ur10, "dh": {k: v + [0] if isinstance(v, list) else v
                                                 for k, v in ur10["dh"].items()}}, r"list of 6 numbers")


def _measurement_cases(base):
    """Adversarial measurement files: values, units, shapes, another robot's data."""
    text = (base / "meas.csv").read_text()
    header, *rows = text.splitlines()
    names = header.split(",")
    table = np.array([[float(v) for v in row.split(",")] for row in rows])

    def csv(matrix, head=header):
        return {"meas.csv": (head + "\n" + "".join(",".join(f"{v:.6f}" for v in r) + "\n" for r in matrix)).encode()}

    def scaled(columns, factor):
        changed = table.copy()
        changed[:, [names.index(c) for c in columns]] *= factor
        return csv(changed)

    position, measured, joints = ["x", "y", "z"], ["mx", "my", "mz"], [f"j{i}" for i in range(1, 7)]
    for column in ("j2", "x", "mx", "mz"):
        for value in ("1e308", "nan", "inf", "-1e-320", "9" * 400, "", "text", "0x10", "1,5"):
            changed = [row.split(",") for row in rows]
            changed[7][names.index(column)] = value
            yield Case("measurements", f"{column} on line 9 = {value[:12]!r}",
                       {"meas.csv": (header + "\n" + "\n".join(map(",".join, changed)) + "\n").encode()})
    yield Case("measurements", "measured in metres", scaled(measured, 1e-3), r"measured in metres\?",
               ("calibrate", "validate"))
    yield Case("measurements", "everything in metres", scaled(position + measured, 1e-3))
    yield Case("measurements", "measured in micrometres", scaled(measured, 1e3), r"another unit",
               ("calibrate", "validate"))
    yield Case("measurements", "joints in radians", scaled(joints, math.pi / 180))
    yield Case("measurements", "measured = commanded", csv(np.column_stack([table[:, :12], table[:, 6:9]])))
    yield Case("measurements", "measured constant", csv(np.column_stack([table[:, :12], np.tile(table[0, 12:], (len(
        table), 1))])))
    yield Case("measurements", "measured 1e300", csv(np.column_stack([table[:, :12], np.full((len(table), 3), 1e300)])))
    yield Case("measurements", "j2 beyond its limits (+720 deg)", csv(table + np.eye(15)[1] * 720))
    yield Case("measurements", "x..c of another robot", csv(np.column_stack([table[:, :6], table[:, 6:9] * 0.7,
                                                                            table[:, 9:]])))
    yield Case("measurements", "rows shuffled", csv(table[np.random.default_rng(0).permutation(len(table))]))
    yield Case("measurements", "one row x1000", csv(np.repeat(table[:1], 1000, axis=0)))
    yield Case("measurements", "every row x40", csv(np.repeat(table, 40, axis=0)))
    yield Case("measurements", "2 rows", csv(table[:2]))
    yield Case("measurements", "header only", {"meas.csv": (header + "\n").encode()}, r"no data rows")
    yield Case("measurements", "no mz", csv(table[:, :14], ",".join(names[:14])), r".")
    yield Case("measurements", "j6 missing", csv(np.delete(table, 5, axis=1), ",".join(names[:5] + names[6:])))
    yield Case("measurements", "a column given twice", csv(np.column_stack([table, table[:, :1]]), header + ",j1"))
    yield Case("measurements", "2,000 columns", csv(np.tile(table, (1, 134)), ",".join(names * 134)), r".")
    yield Case("measurements", "the header x100,000", {"meas.csv": (header + "\n").encode() * 100_000}, r":2: ")
    yield Case("measurements", "semicolons", {"meas.csv": text.replace(",", ";").encode()}, r".")
    yield Case("measurements", "CRLF and a BOM", {"meas.csv": ("\ufeff" + text.replace("\n", "\r\n")).encode()})
    yield Case("measurements", "quoted numbers",
               {"meas.csv": "\n".join(",".join(f'"{v}"' for v in line.split(",")) for line in text.splitlines())
                .encode()})
    yield Case("measurements", "mrx, mry, mrz of junk", csv(np.column_stack([table, np.full((len(table), 3), 1e308)]),
                                                              header + ",mrx,mry,mrz"))
    yield Case("measurements", "a quarter of the rows 5 mm off",
               csv(table + np.outer(np.arange(len(table)) % 4 == 0, np.eye(15)[12] * 5.0)))


def _layout_cases():
    """Adversarial layout files."""
    for name, text in (
        ("unknown key", "columns: {}\nmagic: 1\n"),
        ("columns a list", "columns: [j1, j2]\n"),
        ("a column of nothing", "columns: {j1: nothing}\n"),
        ("field unknown", "columns: {zz: j1}\n"),
        ("delimiter of 3 characters", "delimiter: ';;;'\n"),
        ("delimiter newline", "delimiter: \"\\n\"\n"),
        ("decimal comma with comma delimiter", "decimal: ','\n"),
        ("units parsec", "units: {position: parsec}\n"),
        ("units a list", "units: [mm]\n"),
        ("rotation XYZW", "rotations: {orientation: XYZW}\n"),
        ("frame moon", "frame: moon\n"),
        ("quaternion without q columns", "rotations: {orientation: quaternion}\n"),
        ("mx read twice", "columns: {mx: mx, my: mx}\n"),
        ("expression of 1,000 terms", "columns: {mx: " + "+".join(["mx"] * 1000) + "}\n"),
        ("positions in metres", "units: {position: m}\n"),
    ):
        yield Case("layout", name, {"layout.yaml": text.encode()})


def cases(base, per_kind=40, seed=26, giant=0):
    """Every adversarial case and ``per_kind`` seeded random mutations of each file (value and byte mutations).

    Parameters
    ----------
    base : Path
        A folder written by `build_base`.
    per_kind : int
        Random mutations per file and operator family.
    seed : int
    giant : int
        Megabytes of the giant-file cases (0: none).
    """
    base = Path(base)
    rng = random.Random(seed)
    sidecar = {"model.yaml.npz": (base / "model.yaml.npz").read_bytes()}
    for kind in KINDS:
        name = FILES[kind]
        data = (base / name).read_bytes()
        extra = sidecar if kind == "model" else None
        yield from (dataclasses.replace(c, files={**c.files, **(extra or {})}) if extra and "sidecar" not in c.name
                    else c for c in _file_attacks(kind, name, data, giant))
        yield from _byte_cases(kind, name, data, rng, per_kind, extra)
        if kind != "measurements":
            yield from (dataclasses.replace(c, files={**c.files, **(extra or {})}) for c in _yaml_attacks(kind, name, data))
            yield from (dataclasses.replace(c, files={**c.files, **(extra or {})})
                        for c in _value_cases(kind, name, data, rng, per_kind))
    yield from _sidecar_cases(base)
    yield from _model_cases(base)
    yield from _robot_cases()
    yield from _measurement_cases(base)
    yield from _layout_cases()


def write_case(case, folder):
    """Write ``case``'s files into a new ``folder``; the path of the file its commands read."""
    folder = Path(folder)
    folder.mkdir(parents=True)
    for name, data in case.files.items():
        (folder / name).write_bytes(data)
    return folder / FILES[case.kind]


def run(case, base, folder, skip=()):
    """Run every command of ``case``'s kind (but those named in ``skip``) on its files written into ``folder``, in
    this process.

    Returns
    -------
    list of Outcome
    """
    path = write_case(case, folder)
    outcomes = []
    for k, command in enumerate(COMMANDS[case.kind]):
        if command[0] in skip:
            continue
        out = Path(folder) / f"out{k}"
        out.mkdir()
        argv = tuple(a.format(base=base, file=path, out=out) for a in command)
        stderr = io.StringIO()
        start = time.perf_counter()
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            code = main(list(argv))
        seconds = time.perf_counter() - start
        outcomes.append(Outcome(argv, code, seconds, stderr.getvalue(), tuple(p.name for p in out.iterdir())))
        shutil.rmtree(out)
    return outcomes


def violations(case, outcomes, folder):
    """What broke the contract in ``outcomes`` of ``case`` run in ``folder``, one line each (none: it held).

    The contract: exit 0 or 1 (accepted), or 2 (refused) with a message
    naming the hostile file (its folder, unique to the case) and nothing
    written; a case that states its refusal is refused with that message.
    """
    found = []
    for outcome in outcomes:
        command = outcome.argv[0]
        last = outcome.message.strip().splitlines()[-1][:300] if outcome.message.strip() else "(no message)"
        expected = case.refusal and (case.by is None or command in case.by)
        if outcome.code not in (0, 1, 2):
            found.append(f"{command}: exit {outcome.code}: {last}")
        elif outcome.code == 2 and not (str(folder) in outcome.message or re.search(_ALSO_NAMED[case.kind],
                                                                                      outcome.message)):
            found.append(f"{command}: refused without naming the file: {last}")
        elif outcome.code == 2 and outcome.written:
            found.append(f"{command}: refused but wrote {', '.join(outcome.written)}")
        elif expected and outcome.code != 2:
            found.append(f"{command}: accepted (exit {outcome.code}), expected a refusal matching {case.refusal!r}")
        elif expected and not re.search(case.refusal, outcome.message):
            found.append(f"{command}: refused, but not as {case.refusal!r}: {last}")
    return found


_ALSO_NAMED = {  # what else a refusal may name instead of the hostile file: what it is about
    "robot": r"robot ur10\b|program\.csv:\d+|meas\.csv: identified",  # the robot by its name, the program line it
    # cannot run, or the measurements it cannot have made ("data of another robot")
    "layout": r"meas\.csv",  # the measurements as read through the layout
    "model": r"(?!)",
    "measurements": r"(?!)",
}
