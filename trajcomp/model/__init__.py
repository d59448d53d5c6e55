"""The compensation model: what calibration identified and what it predicts.

`compensation_model` (the model and its modes), `model_file` (its YAML and
sidecar), the residual fields (`grid` on lattices, `interpolate` on
scattered points), `linear` (the paper's per-axis linear correction),
`joint_errors` (joint-angle error terms), `stats` (error statistics and
cross-validation splits) and `landing` (how far a compensated target may
land from where it should).
"""
