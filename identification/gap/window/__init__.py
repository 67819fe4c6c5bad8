"""The gap diagnosis's window test: its regressors and the surrogate calibration."""
