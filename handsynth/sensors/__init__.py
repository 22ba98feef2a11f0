"""Sensor-based hand measurement, one subpackage per system.

* :mod:`handsynth.sensors.trackers` -- finger joint centres from two 6-DOF
  magnetic trackers (patent JP2010-88628, SPEC.md section 2).
* :mod:`handsynth.sensors.imu` -- finger tracking with inertial measurement
  units (SPEC.md section 3).
* :mod:`handsynth.sensors.glove` -- all joint angles from a few-sensor data
  glove (SPEC.md section 4).
* :mod:`handsynth.sensors.common` -- rotation conventions and helpers they share.

Each system has its own recordings, simulation and estimators and imports only
:mod:`handsynth.models`, :mod:`handsynth.errors` and
:mod:`handsynth.sensors.common` (checked by the import contracts in
``pyproject.toml``).
"""
