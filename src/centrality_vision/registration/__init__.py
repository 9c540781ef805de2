"""Point-set registration: CPD (rigid, similarity, affine, non-rigid), GPD and ICP.

Every estimator takes ``fit(moving, fixed)``: the moving set Y (M x D) is transformed onto
the fixed set X (N x D). CPD's variants share one EM loop and one E-step computed in log
space; GPD (the thesis' Graph-based Point Drift) is any CPD with a centrality prior fed into
that same E-step (thesis eq. 5.10: the posterior of each pair is multiplied by a histogram
weight of the moving point's centrality and a Gaussian in the centrality difference).
The estimators are scikit-learn estimators (``clone``, ``get_params``/``set_params``);
by default CPD and GPD run on both sets centred and scaled to unit RMS radius, so their
parameters are unit-free and the results equivariant under translation and scaling.
"""

from ..transforms import AffineTransform, NonRigidTransform, RigidTransform, SimilarityTransform, random_rotation
from ._cpd import AffineCPD, IterationInfo, NonRigidCPD, RigidCPD, Snapshots, alignment_error, initial_sigma2
from ._estep import CentralityPrior, Posteriors
from ._gpd import GPD, GRAPHS, centrality_prior, normalize_centrality
from ._icp import ICP, estimate_normals
from ._multiscale import ComposedTransform, MultiscaleCPD

__all__ = [
    "RigidCPD",
    "AffineCPD",
    "NonRigidCPD",
    "MultiscaleCPD",
    "ComposedTransform",
    "GPD",
    "ICP",
    "estimate_normals",
    "GRAPHS",
    "IterationInfo",
    "Snapshots",
    "Posteriors",
    "CentralityPrior",
    "centrality_prior",
    "normalize_centrality",
    "initial_sigma2",
    "alignment_error",
    "RigidTransform",
    "SimilarityTransform",
    "AffineTransform",
    "NonRigidTransform",
    "random_rotation",
]
