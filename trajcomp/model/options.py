"""The model's modes and residual field kinds: the names ``--mode`` and ``calibrate --interpolation`` offer.

Plain constants, no numpy: a command's ``--help`` builds its parser from
them without loading the model (`trajcomp.model.compensation_model`,
`trajcomp.model.grid`, `trajcomp.model.interpolate` and
`trajcomp.model.joint_errors` import them from here).
"""

MODES = ("none", "linear", "dh", "grid", "composite")  # what a model predicts with: nothing, or its stages
LATTICE_KINDS = ("idw8", "trilinear")  # residual fields on a lattice (`trajcomp.model.grid`)
KNN_KIND = "knn"  # residual field on scattered points, k nearest neighbours (`trajcomp.model.interpolate.KNN`)
RBF_KIND = "rbf"  # residual field on scattered points, radial basis functions (`trajcomp.model.interpolate.RBF`)
FIELD_KINDS = (*LATTICE_KINDS, KNN_KIND, RBF_KIND)  # residual fields over positions
KRIGING_KIND = "kriging"  # a re-calibration's correction from a few rows (`trajcomp.model.interpolate.Kriging`)
GP_KIND = "gp"  # calibrate's field on top of a joint residual, kriged (`trajcomp.model.interpolate.GaussianField`)
JOINT_KIND = "joint"  # joint-angle error terms (`trajcomp.model.joint_errors`)
