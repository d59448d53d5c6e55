"""A program cut off in transfer is refused with its file and line, as its controller refuses it."""

import re
from pathlib import Path

import pytest

from trajcomp import formats
from trajcomp.errors import ReadError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
CASES = {  # (example, lines kept from the end removed, the refusal: where and what)
    "krl without END": ("kuka/weld.src", 1, r"weld\.src:1: DEF has no END \(the text ends at line 10\)"),
    "rapid without ENDMODULE": ("abb/Weld.mod", 1, r"Weld\.mod:1: MODULE has no ENDMODULE \(the text ends at line 14\)"),
    "rapid without ENDPROC": ("abb/Weld.mod", 2, r"Weld\.mod:8: PROC has no ENDPROC \(the text ends at line 13\)"),
    "fanuc without /END": ("fanuc/WELD.LS", 1, r"WELD\.LS:\d+: no /END after it"),
    "urscript without end": ("ur/weld.script", 2, r"weld\.script:1: DEF has no END \(the text ends at line 6\)"),
}


@pytest.mark.parametrize("case", CASES)
def test_a_cut_program_is_refused_naming_file_and_line(case, tmp_path):
    example, removed, refusal = CASES[case]
    source = EXAMPLES / example
    for sibling in source.parent.iterdir():  # the KRL .dat comes along
        (tmp_path / sibling.name).write_bytes(sibling.read_bytes())
    cut = tmp_path / source.name
    cut.write_text("".join(source.read_text().splitlines(keepends=True)[:-removed]))
    with pytest.raises(ReadError, match=refusal + ".*the program is cut off"):
        formats.read(cut)


def test_blocks_closed_inside_the_routine_do_not_close_it(tmp_path):
    """An ENDIF, ENDWHILE or an ``end`` of an ``if`` is not the routine's end."""
    krl = tmp_path / "loop.src"
    krl.write_text("DEF loop( )\n  IF $IN[1] THEN\n    PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\n  ENDIF\n")
    with pytest.raises(ReadError, match=r"loop\.src:1: DEF has no END"):
        formats.read(krl)
    krl.write_text(krl.read_text() + "END\n")
    assert len(formats.read(krl).motions) == 1
    script = tmp_path / "loop.script"
    script.write_text("def loop():\n  if True:\n    movej([0, -1.57, 1.57, 0, 0, 0])\n  end\n")
    with pytest.raises(ReadError, match=re.escape("loop.script:1: DEF has no END")):
        formats.read(script)
    script.write_text(script.read_text() + "end\n")
    assert len(formats.read(script).motions) == 1
