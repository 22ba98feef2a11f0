"""Finger tracking with inertial measurement units (SPEC.md section 3).

Simulated MEMS IMUs on the forearm, the back of the hand and every phalanx,
orientation filters, sensor-to-joint vectors and joint angles.  Not written
yet: the package reserves the name.
"""
