"""Batch compensation: many files, one report line and summary entry each, a bad file never stops the rest."""

import contextlib
import json
import socket
import warnings
from pathlib import Path

import pytest

from trajcomp import formats
from trajcomp.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"


def _krl(folder, name, extra=""):
    """A copy of the example weld program as ``name``.src/.dat, ``extra`` lines added before END."""
    src = (EXAMPLES / "weld.src").read_text().replace("DEF weld(", f"DEF {name}(")
    (folder / f"{name}.src").write_text(src.replace("\nEND", f"\n{extra}END") if extra else src)
    (folder / f"{name}.dat").write_text((EXAMPLES / "weld.dat").read_text().replace("DEFDAT weld", f"DEFDAT {name}"))
    return folder / f"{name}.src"


@pytest.fixture
def cell(tmp_path):
    """Three good programs, one with a motion computed at run time, one that is not a program."""
    programs = tmp_path / "programs"
    programs.mkdir()
    for name in ("alpha", "beta", "gamma"):
        _krl(programs, name)
    _krl(programs, "runtime", "LIN P1:{X 10}\n")
    (programs / "broken.src").write_bytes(b"\x00\x01 not a program")
    return programs


def _summary(path):
    return {Path(f["input"]).name: f for f in json.loads(path.read_text())["files"]}


def test_a_failing_file_does_not_stop_the_others(cell, tmp_path, kuka_model, capsys):
    out = tmp_path / "out"
    code = main(["compensate", str(cell), "--model", str(kuka_model), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2  # one file could not be read
    files = _summary(out / "summary.json")
    assert {name: f["status"] for name, f in files.items()} == {
        "alpha.src": "pass", "beta.src": "pass", "gamma.src": "pass", "runtime.src": "fail", "broken.src": "error"}
    assert "not a text file" in files["broken.src"]["message"]
    assert "ERROR" in err and "broken.src" in err
    for name in ("alpha", "beta", "gamma", "runtime"):
        assert (out / f"{name}.src").exists() and (out / f"{name}.dat").exists()
        assert formats.read(out / f"{name}.src").targets[0].pose is not None
    assert not (out / "broken.src").exists()


def test_exit_1_when_a_file_fails_its_verdict_and_none_is_bad(cell, tmp_path, kuka_model):
    (cell / "broken.src").unlink()
    summary = tmp_path / "s.json"
    assert main(["compensate", str(cell / "*.src"), "--model", str(kuka_model), "-o", str(tmp_path / "out"),
                 "--summary", str(summary)]) == 1
    document = json.loads(summary.read_text())
    assert document["schema"] == "trajcomp-batch/1"
    assert document["counts"] == {"pass": 3, "fail": 1, "error": 0, "crash": 0}


def test_parallel_runs_write_what_a_serial_run_writes(cell, tmp_path, kuka_model):
    (cell / "broken.src").unlink()
    (cell / "runtime.src").unlink()
    serial, parallel = tmp_path / "serial", tmp_path / "parallel"
    assert main(["compensate", str(cell), "--model", str(kuka_model), "-o", str(serial)]) == 0
    assert main(["compensate", str(cell), "--model", str(kuka_model), "-o", str(parallel), "--jobs", "2"]) == 0
    for path in serial.glob("*.[sd][ra][ct]"):
        assert (parallel / path.name).read_bytes() == path.read_bytes()


def test_a_local_dask_cluster_runs_the_same_batch(cell, tmp_path, kuka_model):
    """The same programs as a serial run, beside another cluster: with Dask's HTTP port (8787) taken, as by a second
    batch of a build pipeline at once, the scheduler said so on stderr as a Python warning, outside the report."""
    pytest.importorskip("dask.distributed")
    (cell / "broken.src").unlink()
    serial, dask = tmp_path / "serial", tmp_path / "dask"
    assert main(["compensate", str(cell), "--model", str(kuka_model), "-o", str(serial)]) == 1
    held = socket.socket()
    held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    with held, warnings.catch_warnings(record=True) as caught:
        with contextlib.suppress(OSError):  # taken already: held by another process, as the test wants
            held.bind(("", 8787))
            held.listen()
        warnings.simplefilter("always")
        assert main(["compensate", str(cell), "--model", str(kuka_model), "-o", str(dask),
                     "--scheduler", "local", "--jobs", "2"]) == 1
    assert [str(w.message) for w in caught if "in use" in str(w.message)] == []
    assert _summary(dask / "summary.json")["runtime.src"]["status"] == "fail"
    for path in serial.glob("*.src"):
        assert (dask / path.name).read_bytes() == path.read_bytes()


def test_inputs_whose_outputs_would_collide_are_refused(tmp_path, kuka_model, capsys):
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        _krl(tmp_path / folder, "weld")
    code = main(["compensate", str(tmp_path / "a"), str(tmp_path / "b"), "--model", str(kuka_model),
                 "-o", str(tmp_path / "out")])
    assert code == 2
    assert "would both be written to" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_pattern_matching_nothing_is_an_error(tmp_path, kuka_model, capsys):
    assert main(["compensate", str(tmp_path / "*.src"), "--model", str(kuka_model), "-o", str(tmp_path / "o")]) == 2
    assert "no program file" in capsys.readouterr().err


def test_one_missing_file_is_an_error_not_a_folder(tmp_path, kuka_model, capsys):
    assert main(["compensate", str(tmp_path / "nope.src"), "--model", str(kuka_model),
                 "-o", str(tmp_path / "out.src")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert not (tmp_path / "out.src").exists()


def test_a_crash_in_one_file_is_a_bug_report_and_exit_3(cell, tmp_path, kuka_model, monkeypatch):
    read = formats.read

    def crashing(path, *args, **kwargs):
        if Path(path).name == "beta.src":
            raise IndexError("a bug")
        return read(path, *args, **kwargs)

    monkeypatch.setattr(formats, "read", crashing)
    out = tmp_path / "out"
    assert main(["compensate", str(cell / "alpha.src"), str(cell / "beta.src"), "--model", str(kuka_model),
                 "-o", str(out), "--jobs", "1"]) == 3
    files = _summary(out / "summary.json")
    assert files["alpha.src"]["status"] == "pass" and files["beta.src"]["status"] == "crash"
    message = files["beta.src"]["message"]
    assert "this is a bug" in message and "IndexError: a bug" in message
    Path(message.rsplit("traceback saved in ", 1)[1]).unlink()


def test_reports_mirror_the_input_folders_as_the_programs_do(tmp_path, kuka_model):
    cam = tmp_path / "cam"
    for folder in ("a", "b"):
        (cam / folder).mkdir(parents=True)
        _krl(cam / folder, "weld")
    out = tmp_path / "out"
    assert main(["compensate", str(cam), "--model", str(kuka_model), "-o", str(out), "--report", str(out / "reports"),
                 "--jobs", "1"]) == 0
    files = json.loads((out / "summary.json").read_text())["files"]
    for folder in ("a", "b"):
        (entry,) = [f for f in files if Path(f["input"]).parent.name == folder]
        report = out / "reports" / folder / "weld.src.json"
        assert str(report) in entry["outputs"] and (out / folder / "weld.src").exists()
        provenance = json.loads(report.read_text())
        assert str(cam / folder / "weld.src") in json.dumps(provenance)
        assert str(cam / ("b" if folder == "a" else "a")) not in json.dumps(provenance)
    assert not (out / "reports" / "weld.src.json").exists()


def test_outputs_that_only_their_extensions_kept_apart_are_refused_before_anything_is_written(tmp_path, kuka_model,
                                                                                               capsys):
    cam = tmp_path / "cam"
    cam.mkdir()
    _krl(cam, "weld")
    (cam / "weld.csv").write_text((Path(__file__).resolve().parents[2] / "examples" / "programs" / "csv"
                                   / "weld.csv").read_text())
    code = main(["compensate", str(cam), "--model", str(kuka_model), "-o", str(tmp_path / "out"), "--to", "csv"])
    assert code == 2 and "would both be written to" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_batch_written_into_its_own_folder_is_refused_with_advice_about_the_folder(tmp_path, kuka_model, capsys):
    cam = tmp_path / "cam"
    cam.mkdir()
    _krl(cam, "weld")
    before = {p.name: p.read_bytes() for p in cam.iterdir()}
    assert main(["compensate", str(cam), "--model", str(kuka_model), "-o", str(cam)]) == 2
    err = capsys.readouterr().err
    assert "would overwrite the input" in err and "give -o another folder" in err and "--summary" not in err
    assert {p.name: p.read_bytes() for p in cam.iterdir()} == before

