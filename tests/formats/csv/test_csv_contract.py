"""Program CSV keeps the language contract: read, write and every capability it declares (tests/formats/contract.py)."""

from pathlib import Path

from tests.formats.contract import Samples, check_language

DATA = Path(__file__).parents[2] / "data" / "programs"


def test_csv_keeps_its_contract(tmp_path):
    check_language("csv", Samples(DATA / "csv" / "path.csv", "kuka_kr6_r900"), tmp_path)
