"""ABB RAPID keeps the language contract: read, write and every capability it declares (tests/formats/contract.py)."""

from pathlib import Path

from tests.formats.contract import Samples, check_language

DATA = Path(__file__).parents[2] / "data" / "programs"
TOOLS = "".join(f"  PERS tooldata {name} := [TRUE,[[0,0,{z}],[1,0,0,0]],[2,[0,0,100],[1,0,0,0],0,0,0]];\n"
                for name, z in (("tA", 100), ("tB", 200)))
SHARED_POINT = {"Shared.mod": "MODULE Shared\n" + TOOLS
                + "  CONST robtarget p10:=[[1200,0,1200],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
                "  PROC main()\n    MoveJ p10, v100, fine, tA;\n    MoveL p10, v100, fine, tB;\n  ENDPROC\nENDMODULE\n"}


def test_rapid_keeps_its_contract(tmp_path):
    task = DATA / "real" / "rapid" / "keen1949_TASK1"  # Homeing_Init moves to points other modules declare
    samples = Samples(DATA / "rapid" / "Welding.mod", "abb_irb4600", {"shared_point": SHARED_POINT},
                      (task, "PROGMOD/Homeing_Init.mod"))
    check_language("rapid", samples, tmp_path)
