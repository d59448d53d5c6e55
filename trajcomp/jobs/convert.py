"""The conversion job: a program file rewritten in another language (``trajcomp convert``), no model.

Into its own language a program is written back as it is, every field as
written; into another, its poses, configuration data and speeds are carried
over (`trajcomp.compensation.program_rewrite.convert_program`): motions
computed at run time are written as comments, and a speed that cannot be
carried over is written as the language's slowest and listed.
"""

import dataclasses

from trajcomp import formats
from trajcomp.compensation.program_rewrite import convert_program
from trajcomp.jobs import batch
from trajcomp.programs.program import place_text

LISTED = 20  # motions whose speed was not carried over named one by one


@dataclasses.dataclass(frozen=True)
class ConvertRun:
    """What a conversion did with one program file.

    Attributes
    ----------
    result : batch.FileResult
        Pass, or fail (written, but with every motion a comment, or speeds
        set at the slowest): the files written, the line to show and why it
        fails.
    warnings : tuple of str
        The first `LISTED` motions whose speed could not be carried over, each with why.
    """

    result: batch.FileResult
    warnings: tuple = ()


@dataclasses.dataclass(frozen=True)
class ConvertJob:
    """Rewrite one program file in the language of its output (or ``to_format``).

    ``robot`` (a `trajcomp.arm.robot.Robot`, optional) computes the
    configuration data of Cartesian targets and converts between joint and
    TCP speeds; ``tools`` and ``frames`` are values the program uses but
    does not define (T (4, 4), mm). Other attributes are the options of
    ``trajcomp convert``.
    """

    robot: object = None
    tools: dict = dataclasses.field(default_factory=dict)
    frames: dict = dataclasses.field(default_factory=dict)
    from_format: str = None
    to_format: str = None
    in_place: bool = False

    def run(self, path, output):
        """Convert ``path`` into ``output``: a `ConvertRun`."""
        to_format = formats.find_format(output, self.to_format)
        # into its own language every number is kept as written: a point used with two tools needs no copy per use
        same = to_format == formats.find_format(path, self.from_format)
        program = formats.read(path, self.from_format, copies=not same)
        if self.robot is not None:
            formats.check_robot_language(output, to_format, self.robot, "the arm --robot names")
        converted = convert_program(program, to_format.name, robot=self.robot, tools=self.tools, frames=self.frames)
        protect = [] if self.in_place else formats.input_paths(path, program)
        outputs = tuple(map(str, formats.write(output, converted, to_format.name, protect=protect)))
        written = ", ".join(outputs)
        if converted is program:  # its own language: every field kept as written
            line = f"wrote {written}: {len(program.motions)} motions, as written"
            return ConvertRun(batch.FileResult(str(path), outputs, lines=(line,)))
        skipped = len(program.runtime_motions())
        line = (f"wrote {written}: {len(converted.motions) - skipped} motions"
                + (f", {skipped} computed at run time written as comments" if skipped else ""))
        if skipped and skipped == len(converted.motions):  # a file of comments: nothing the arm could run
            first = program.runtime_motions()[0]
            why = (f"every motion of {path} is computed at run time, so {outputs[0]} holds comments only, no motion "
                   f"(the first, {place_text(program.place(first))}: {first.reason})")
            return ConvertRun(batch.FileResult(str(path), outputs, batch.FAIL, why, (line,)))
        unknown = [m for m in converted.motions if m.speed_why and m.target is not None]  # written at the slowest
        warnings = tuple(f"{program.location(m)}: speed of {m.text!r}: {m.speed_why}" for m in unknown[:LISTED])
        if not unknown:
            return ConvertRun(batch.FileResult(str(path), outputs, lines=(line,)))
        more = f" (the first {LISTED} listed)" if len(unknown) > LISTED else ""
        why = (f"{len(unknown)} motion(s) whose speed could not be carried over are written at {to_format.name}'s "
               f"slowest speed{more}: set their speeds before running")
        return ConvertRun(batch.FileResult(str(path), outputs, batch.FAIL, why, (line,)), warnings)
