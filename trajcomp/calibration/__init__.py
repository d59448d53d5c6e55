"""The calibration half: plan measurements, read them, identify a model, validate it.

`measurement_plan` (grids and orientations to measure), `virtual_arm` (a
virtual arm with known errors), `measurements` and `layout` (reading
laser-tracker files by an explicit column layout), `orientations` (whether
measurements locate the flange), `identify` (DH, tool and tracker
registration by least squares), `plausibility` (refusing data that cannot
be what it claims) and `calibrate` (the whole run, which yields a
`trajcomp.model.compensation_model.CompensationModel`).
"""
