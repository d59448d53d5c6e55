"""Other ways CAM post-processors write the benchmark's helix: each a text rewrite of `trajcomp convert`'s program.

`bench_scale.py languages` times every form of a language beside the
program `trajcomp convert` writes (e.g. KRL's motions to points of the
.dat, ``LIN XP1 C_DIS``), as post-processors write them: e.g. RoboDK's and
SprutCAM's KUKA posts write each point inline in the .src
(``LIN {X 446.0,Y 70.0,Z 635.0,A 0.0,B 90.0,C 0.0} C_DIS``, no .dat).

``FORMS[language][name](path, folder) -> path``: the program at ``path``
(as converted) written in that form into ``folder``, its new path.
"""

import re
from pathlib import Path

FORMS = {}


def form(language, name):
    """Register the decorated function as ``FORMS[language][name]``."""
    def register(make):
        FORMS.setdefault(language, {})[name] = make
        return make
    return register


# KRL

@form("krl", "inline")
def krl_inline(path, folder):
    """The .src with each motion's point written inline (its S and T left out, as LIN ignores them), no .dat."""
    path = Path(path)
    points = dict(re.findall(r"^DECL E6POS (\w+)=\{([^}]*?)(?:,S \d+,T \d+)?\}$",
                             path.with_suffix(".dat").read_text(), re.M))
    name = f"{path.stem}_inline"
    text = re.sub(r"^DEF \w+\(", f"DEF {name}(", path.read_text(), count=1, flags=re.M)
    text = re.sub(r"^(\s*(?:LIN|PTP) )(\w+)", lambda m: f"{m.group(1)}{{{points[m.group(2)]}}}", text, flags=re.M)
    out = Path(folder) / f"{name}.src"
    out.write_text(text)
    return out
