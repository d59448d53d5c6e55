"""URScript keeps the language contract: read, write and every capability it declares (tests/formats/contract.py)."""

from pathlib import Path

from tests.formats.contract import Samples, check_language

DATA = Path(__file__).parents[2] / "data" / "programs"
SHARED_POINT = {"shared.script": "def shared():\n  pick = p[0.5, 0.1, 0.4, 0, 3.14159, 0]\n"
                "  set_tcp(p[0, 0, 0.1, 0, 0, 0])\n  movej(pick, a=1.4, v=1.05)\n"
                "  set_tcp(p[0, 0, 0.2, 0, 0, 0])\n  movel(pick, a=1.2, v=0.25)\nend\n"}


def test_urscript_keeps_its_contract(tmp_path):
    samples = Samples(DATA / "urscript" / "pick.script", "ur10", {"shared_point": SHARED_POINT})
    check_language("urscript", samples, tmp_path)
