"""The seed papers' filters, one small class per paper's filter: their equations in the papers'
notation with the equation numbers, their values and rules as they are, and no switch of ours.

    PaperComplementaryFilter     Gui et al. 2015 eq. 1-2; Das & Mary eq. 1
    PaperKalmanFilter            Gui et al. 2015 eq. 5-26; Das & Mary eq. 16-27
    PaperGainScheduledFilter     Duong Quoc et al. eq. 7-13 (Mahony et al. 2008)
    PaperUnscentedKalmanFilter   Duong Quoc et al. eq. 14-17
    PaperPositionKalmanFilter    Safitri et al. eq. 20-29

They are what `--preset paper` runs (fusion_core.registry.create), each under the model name,
inputs and outputs of the recommended estimator it is the reference of, so that an FMU of
either preset drops into the same connections. The recommended estimators (fusion_core.ESTIMATORS)
are built on the same equations, which live here as module functions.
"""

from .complementary import PaperComplementaryFilter
from .kalman import PaperKalmanFilter
from .mgcf import PaperGainScheduledFilter
from .position import PaperPositionKalmanFilter
from .ukf import PaperUnscentedKalmanFilter

__all__ = ["PaperComplementaryFilter", "PaperGainScheduledFilter", "PaperKalmanFilter",
           "PaperPositionKalmanFilter", "PaperUnscentedKalmanFilter"]
