"""Published figures of the FOG start-up paper, for the report that sets our tables beside the
paper.

Copied from the paper (facts only); the same numbers are in
../shared/reference/seed004_table*.csv, and tests/report checks the copy against them when
../shared is present.  Kept in the package because nothing may read ../shared at run time.

Source: "A FOG start-up drift compensation method at full temperatures", the FOG start-up paper of
this
project (Opto-Electronic Engineering), Tables 1-3.
"""

from __future__ import annotations

__all__ = ["SEED004_TEMPERATURES_C", "SEED004_TABLE3_HEADING_RMSE_DEG",
           "SEED004_TABLE2_DRIFT_DPH", "SEED004_TABLE1_SVR", "TAO2019_BIAS_STABILITY",
           "LIANG2021_RVR_OVER_LS_PCT", "CHENG2015_TABLE2_MSD"]

#: Start temperatures of Table 3 [degC].
SEED004_TEMPERATURES_C = (-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0)

#: Table 3: start-up north-finding heading RMSE [deg] by method; last entry is the mean.
SEED004_TABLE3_HEADING_RMSE_DEG = {
    "before": (0.0284, 0.0181, 0.0216, 0.0205, 0.0303, 0.0171, 0.0106, 0.0209),
    "BP": (0.0284, 0.0113, 0.0143, 0.0137, 0.0209, 0.0106, 0.0100, 0.0156),
    "PSO-SVR": (0.0146, 0.0088, 0.0120, 0.0144, 0.0186, 0.0054, 0.0060, 0.0114),
    "GWO-SVR": (0.0110, 0.0051, 0.0132, 0.0093, 0.0194, 0.0077, 0.0096, 0.0108),
    "SSA-SVR": (0.0113, 0.0087, 0.0117, 0.0131, 0.0170, 0.0046, 0.0045, 0.0101),
}

#: Table 2: (MAE, STD) of the drift residual [deg/h]; MAE is None for the denoised data.
SEED004_TABLE2_DRIFT_DPH = {
    "denoised (no compensation)": (None, 0.0134),
    "BP": (0.0056, 0.0073),
    "SVR": (0.0030, 0.0035),
    "SSA-SVR": (0.0025, 0.0031),
}

#: Table 1: SSA-tuned SVR kernel parameters.
SEED004_TABLE1_SVR = {"C": 1.0520, "sigma": 0.9506}


#: Tao, Li, Zheng, Wu and Fu, "High Precision Compensation for a Total Reflection Prism Laser
#: Gyro Bias in Consideration of High Frequency Oscillator Voltage", Sensors 19(13), 2986
#: (2019): bias stability of the compensated test cycle [deg/h] and its improvement [%] by
#: method, the best row of each: uncompensated (Tables 2-5), LS on U_HFO alone (Table 2),
#: stepwise Model 2 on T, dT/dt and U_HFO (Table 3), LSSVM and IR-LSSVM (myriad weights) on
#: T, dT/dt and U_HFO (section 4.4 and Table 5).  The same numbers for IR-LSSVM are in
#: ../shared/reference/seed000_table5_irlssvm_all_inputs.csv.
TAO2019_BIAS_STABILITY = {
    "uncompensated": (0.01850, 0.0),
    "LS": (0.01100, 40.54),
    "stepwise": (0.00842, 54.49),
    "LSSVM": (0.00758, 59.03),
    "IR-LSSVM": (0.00718, 61.19),
}


#: Liang, Tao, Wang, Guo and Zhao, "System-Level Temperature Compensation Method for the RLG-IMU
#: Based on HHO-RVR", Journal of Sensors 2021, 6613574 (abstract and section 4.2, Table 2):
#: how much HHO-RVR betters the cubic least squares on average over the 15 temperature-related
#: parameters of their RLG IMU [%]: RMSE, MAE, R^2 and the residual variance.
LIANG2021_RVR_OVER_LS_PCT = {"rmse": 35.27, "mae": 39.29, "r2": 2.29, "residual_variance": 30.34}

#: Cheng, Qi, Chen and Landry, "Modification of an RBF ANN-Based Temperature Compensation Model
#: of Interferometric Fiber Optical Gyroscopes", Sensors 15(5), 11189-11207 (2015), Table 2:
#: mean square deviation of the gyro output from the known rate in five test experiments,
#: before and after compensation by the RBF network on T, dT and T x dT (as printed).
CHENG2015_TABLE2_MSD = ((1.72e-4, 1.24e-5), (9.90e-4, 1.76e-5), (1.80e-3, 2.05e-5),
                        (2.67e-4, 1.33e-5), (9.29e-4, 0.78e-5))
