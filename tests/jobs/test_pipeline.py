"""One pipeline behind every face: the command line, a batch, the Python API give the same program and verdict.

Each language's example program is compensated (and re-timed) on its
maker's virtual arm through `trajcomp compensate` for one file, through a
batch (a glob pattern, on a worker process) and through
`trajcomp.Compensator.filter_program` and `trajcomp.filter_program`:
every written file is byte-identical across the four, and the verdicts
(each criterion's status) are equal.
"""

import json
import shutil
from pathlib import Path

import pytest

import trajcomp
from trajcomp.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
# language: (program, its arm, the README's calibration cube around it: corner mm, side mm)
CASES = {
    "krl": (EXAMPLES / "programs" / "kuka" / "weld.src", "kuka_kr6_r900", "400,-50,650", "200"),
    "rapid": (EXAMPLES / "programs" / "abb" / "Weld.mod", "abb_irb4600", "1100,-50,1300", "200"),
    "fanuc_ls": (EXAMPLES / "programs" / "fanuc" / "WELD.LS", "fanuc_lrmate200id", "350,-50,480", "150"),
    "urscript": (EXAMPLES / "programs" / "ur" / "weld.script", "ur10", "-750,-200,500", "200"),
    "csv": (EXAMPLES / "programs" / "csv" / "weld.csv", "ur10", "-750,-200,500", "200"),
}


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """``model(robot, corner, side)``: a composite model file of that arm's virtual copy, made once."""
    made = {}

    def model(robot, corner, side):
        if robot not in made:
            folder = tmp_path_factory.mktemp(robot)
            plan, meas, path = folder / "plan.csv", folder / "meas.csv", folder / "model.yaml"
            assert main(["plan", "--robot", robot, f"--cube={corner}", "--side", side, "--step", "50",
                         "-o", str(plan)]) == 0
            assert main(["simulate", str(plan), "--robot", robot, "--seed", "1", "-o", str(meas)]) == 0
            assert main(["calibrate", str(meas), "--robot", robot, "--grid-step", "50", "--folds", "3",
                         "-o", str(path)]) == 0
            made[robot] = path
        return made[robot]

    return model


def _copy(program, folder):
    """The program and the files beside it that share its stem (a KRL .dat) copied into ``folder``."""
    folder.mkdir()
    for path in program.parent.iterdir():
        if path.stem == program.stem:
            shutil.copy(path, folder / path.name)
    return folder / program.name


def _verdict(report_json):
    doc = json.loads(Path(report_json).read_text())
    return doc["verdict"]["result"], {c["id"]: c["status"] for c in doc["verdict"]["criteria"]}


@pytest.mark.parametrize("language", sorted(CASES))
def test_the_command_line_a_batch_and_the_api_write_the_same_program_and_verdict(language, models, tmp_path):
    program, robot, corner, side = CASES[language]
    model = models(robot, corner, side)
    source = _copy(program, tmp_path / "in")
    name = program.name
    out = {face: tmp_path / face for face in ("cli", "batch", "api", "function")}
    for folder in out.values():
        folder.mkdir()

    codes = {"cli": main(["compensate", str(source), "--model", str(model), "-o", str(out["cli"] / name),
                          "--report", str(out["cli"] / "report"), "--jobs", "1"])}
    codes["batch"] = main(["compensate", str(source.parent / f"*{source.suffix}"), "--model", str(model),
                           "-o", str(out["batch"]), "--report", str(out["batch"] / "reports"), "--jobs", "2"])
    run = trajcomp.Compensator(model).filter_program(source, out["api"] / name, report=out["api"] / "report")
    codes["api"] = 0 if run.passed else 1
    function = trajcomp.filter_program(source, out["function"] / name, model=model,
                                       report=out["function"] / "report")
    codes["function"] = 0 if function.passed else 1

    assert len(set(codes.values())) == 1, codes
    assert run.written[0] == out["api"] / name and run.timing is not None  # re-timed, as the command line does
    written = sorted(p.name for p in run.written if not p.name.startswith("report"))
    for face, folder in out.items():
        for file_name in written:
            assert (folder / file_name).read_bytes() == (out["api"] / file_name).read_bytes(), (face, file_name)
    verdicts = {face: _verdict(out[face] / "report.json") for face in ("cli", "api", "function")}
    verdicts["batch"] = _verdict(out["batch"] / "reports" / f"{Path(name).name}.json")
    assert len({json.dumps(v, sort_keys=True) for v in verdicts.values()}) == 1, verdicts
    assert verdicts["api"][0] == ("pass" if run.compliance.passed else "fail")


def test_the_api_keeps_the_speeds_when_asked_and_then_writes_what_the_command_line_does(models, tmp_path):
    program, robot, corner, side = CASES["krl"]
    model = models(robot, corner, side)
    source = _copy(program, tmp_path / "in")
    out = {face: tmp_path / face / program.name for face in ("cli", "api", "timed")}
    for path in out.values():
        path.parent.mkdir()
    assert main(["compensate", str(source), "--model", str(model), "-o", str(out["cli"]), "--retime", "none"]) in (0, 1)
    run = trajcomp.Compensator(model).filter_program(source, out["api"], retime="none")
    assert run.timing is None and run.compliance.doc.get("timing") is None
    assert out["api"].read_bytes() == out["cli"].read_bytes()
    timed = trajcomp.Compensator(model).filter_program(source, out["timed"])  # re-timed by default: the 20 mm/s
    assert timed.timing.cycle_time > 9.0 and timed.compliance.doc["timing"]["cycle_time_s"] > 9.0  # weld kept


def test_the_api_compensates_with_the_model_file_as_it_is_now_not_as_a_cache_kept_it(models, tmp_path):
    """A host application keeps its process: a model file recalibrated under the same name is the one used."""
    import dataclasses
    import hashlib
    import os

    from trajcomp.model.model_file import load_model, save_model

    program, robot, corner, side = CASES["krl"]
    source = _copy(program, tmp_path / "in")
    path = tmp_path / "cell.yaml"
    model = load_model(models(robot, corner, side))
    save_model(path, model)
    out = {name: tmp_path / name / program.name for name in ("before", "after", "reference")}
    for name in out:
        out[name].parent.mkdir()
    trajcomp.filter_program(source, out["before"], model=path, retime="none")
    save_model(path, dataclasses.replace(model, dh_delta=model.dh_delta * 0.5))  # recalibrated: other deltas
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))  # surely a newer version
    after = trajcomp.filter_program(source, out["after"], model=path, retime="none")
    trajcomp.Compensator(load_model(path)).filter_program(source, out["reference"], retime="none")
    points = {name: path.with_suffix(".dat").read_bytes() for name, path in out.items()}  # the corrected targets
    assert points["after"] == points["reference"] != points["before"]
    assert after.compliance.doc["provenance"]["model"]["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()


def _sha(path):
    import hashlib

    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_run_killed_while_its_report_is_drawn_leaves_the_old_program_with_its_own_report(tmp_path, kuka_model):
    """The program and its report are one set: a kill between them left the new program beside the old report."""
    import os
    import signal

    from trajcomp.report.document import Report

    examples = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"
    for version, z in (("a", "790"), ("b", "780")):
        (tmp_path / version).mkdir()
        shutil.copy(examples / "weld.src", tmp_path / version / "weld.src")
        (tmp_path / version / "weld.dat").write_text((examples / "weld.dat").read_text().replace("Z 790", f"Z {z}"))
    out = tmp_path / "out"
    out.mkdir()
    command = ["compensate", "--model", str(kuka_model), "-o", str(out / "weld.src"), "--report", str(out / "weld"),
               "--jobs", "1"]
    assert main(["compensate", str(tmp_path / "a" / "weld.src"), *command[1:]]) in (0, 1)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    pid = os.fork()
    if pid == 0:  # the run killed while it draws its report, its program complete
        Report.html_text = lambda self: os.kill(os.getpid(), signal.SIGKILL)
        main(["compensate", str(tmp_path / "b" / "weld.src"), *command[1:]])
        os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.WIFSIGNALED(status)
    entries = {Path(f["path"]).name: f["sha256"] for f in json.loads((out / "weld.json").read_text())["provenance"]["files"]
               if f["role"] == "output"}
    assert entries == {"weld.src": _sha(out / "weld.src"), "weld.dat": _sha(out / "weld.dat")}
    assert {p.name: p.read_bytes() for p in out.iterdir() if not p.name.startswith(".")} == before
