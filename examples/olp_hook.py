# examples/olp_hook.py: what an offline-programming tool calls when it saves a program
import sys

import trajcomp

model, program, output = sys.argv[1:4]                    # a model of the arm that runs the program
comp = trajcomp.Compensator(model)
run = comp.filter_program(program, output, report=output + ".report")   # as `trajcomp compensate`
print("PASS" if run.passed else "FAIL", ", ".join(map(str, run.written)))
command, joints, correction = comp.filter_target([550, 100, 550, 90, 0, 180])   # one pose: mm, deg
print("command", [round(float(v), 3) for v in command], "correction", [round(float(v), 3) for v in correction])
