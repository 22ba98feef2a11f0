"""All joint angles from a few-sensor data glove (SPEC.md section 4).

Simulated bend-sensor gloves, the regression models with motion mixing and a
synergy baseline.  Not written yet: the package reserves the name.
"""
