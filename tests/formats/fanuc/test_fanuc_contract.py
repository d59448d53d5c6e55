"""FANUC LS keeps the language contract: read, write and every capability it declares (tests/formats/contract.py)."""

from pathlib import Path

from tests.formats.contract import Samples, check_language

DATA = Path(__file__).parents[2] / "data" / "programs"


def test_fanuc_keeps_its_contract(tmp_path):
    task = DATA / "real" / "fanuc" / "ub10200"  # _masterpos moves to a position register of the backup's POSREG.VA
    samples = Samples(DATA / "fanuc" / "PICK_PLACE.LS", "fanuc_lrmate200id", task=(task, "_masterpos.ls"))
    check_language("fanuc_ls", samples, tmp_path)
