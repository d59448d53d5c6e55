"""KUKA KRL keeps the language contract: read, write and every capability it declares (tests/formats/contract.py)."""

from pathlib import Path

from tests.formats.contract import Samples, check_language

DATA = Path(__file__).parents[2] / "data" / "programs"
POINT = "{X 450,Y 20,Z 600,A 0,B 90,C 0,S 2,T 2"
SHARED_POINT = {
    "shared.src": "DEF shared( )\n$TOOL={X 0,Y 0,Z 100,A 0,B 0,C 0}\nPTP XP1\n$TOOL={X 0,Y 0,Z 200,A 0,B 0,C 0}\n"
                  "LIN XP1\nEND\n",
    "shared.dat": f"DEFDAT shared\nDECL E6POS XP1={POINT}}}\nENDDAT\n",
}
KEPT_AXES = {  # XP2, a POS, states no E1: the track stays where XP1 left it
    "rail.src": "DEF rail( )\nPTP XP1\nLIN XP2\nEND\n",
    "rail.dat": f"DEFDAT rail\nDECL E6POS XP1={POINT},E1 500}}\n"
                "DECL POS XP2={X 460,Y 20,Z 600,A 0,B 90,C 0,S 2,T 2}\nENDDAT\n",
}
TASK = {  # main.src moves to XTABLE, a GLOBAL point of the data list table.dat beside it
    "main.src": "DEF main( )\nPTP XP1\nLIN XTABLE\nEND\n",
    "main.dat": f"DEFDAT main\nDECL E6POS XP1={POINT}}}\nENDDAT\n",
    "table.dat": "DEFDAT table PUBLIC\nDECL GLOBAL E6POS XTABLE={X 470,Y 20,Z 600,A 0,B 90,C 0,S 2,T 2}\nENDDAT\n",
}


def test_krl_keeps_its_contract(tmp_path):
    task = tmp_path / "task"
    task.mkdir()
    for name, text in TASK.items():
        (task / name).write_text(text)
    files = {"shared_point": SHARED_POINT, "kept_axes": KEPT_AXES}
    samples = Samples(DATA / "krl" / "weld.src", "kuka_kr6_r900", files, (task, "main.src"))
    check_language("krl", samples, tmp_path / "contract")
