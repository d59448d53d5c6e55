"""The program half: from a program's targets to commands the real arm lands on.

`posture` (the posture each target declares, as nominal joints),
`targets` (the compensated command of each target under a model),
`program` (a program's targets solved, compensated and written back, and
conversion between languages) and `batch` (many files through one job).
"""
