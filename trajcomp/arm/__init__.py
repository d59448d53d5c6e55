"""The arm: its description, kinematics, inverse kinematics and parameter deltas.

`robot` (descriptions and the built-in arms in robots/), `kinematics`
(forward kinematics of DH chains), `ik` with `ik_closed_form`,
`ik_numeric` and `ik_types` (joint solutions of TCP poses), `transforms`
(homogeneous transforms and rotations) and `parameters` (the identifiable
DH, tool and registration deltas). Everything else builds on this wing;
it imports nothing from the others.
"""
