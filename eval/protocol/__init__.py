"""The protocol: metrics, tau calibration, tuning, protocol variants, paired differences, bootstrap intervals, crossovers."""
