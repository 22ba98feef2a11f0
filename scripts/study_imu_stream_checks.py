"""A live stream's checks (:class:`ImuStream`, ``check_s``): faults told, and false alarms.

Usage::

    python scripts/study_imu_stream_checks.py [--seeds 1,2,3,4,5,6] [--checks-s 10,20]

On the held-out configuration's draws of ``--seeds`` (calibrated as ``handsynth imu eval``
calibrates them; 30-s free motions with the elbow fixed and moving, the draw's own sensor
calibration applied), each recording is streamed (packets of 50 samples) as recorded and
with one fault from its start: two sensors' readings exchanged (three random pairs of
sensors a joint of the link model joins), one sensor's stream 20 ms late (three random
sensors of a finger's hinge, the forearm plate or the hand), or one phalanx's sensor
turned half a turn about its z axis on its segment (two random ones).  For each stretch
length of ``--checks-s``: the streams as recorded warned of anything (false alarms), and
the faulty ones warned of their fault naming the sensor, with the stream's time when it was
said (the end of the first stretch that told it).  Also each draw's grasp reaches (24 s,
elbow fixed and moving) as recorded: false alarms.  About 7 min for six seeds.

The last line is machine-readable: ``false_alarms_<s>=<n> grasp_false_alarms_<s>=<n>
told_exchanged_<s>=<n> told_late_<s>=<n> told_turned_<s>=<n> ... recordings=<n> grasps=<n>
exchanged=<n> late=<n> turned=<n>`` for every stretch length s.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np
from study_imu_stream import heldout_draw
from study_imu_swaps import _exchanged, grasp_reaches
from study_imu_turns import _turned

from handsynth.sensors.imu import (
    CARRIED,
    HINGES,
    RIGID,
    ImuStream,
    delayed,
    turn_ratios,
)
from handsynth.sensors.imu._eval import free_trials


def _said(calib, rec, check_s: float) -> list[str]:
    """The stretches' findings of `rec` streamed in packets of 50 samples."""
    stream = ImuStream(calib, rate_hz=rec.rate_hz, sensor_calibration=False, check_s=check_s)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for i in range(0, rec.n, 50):
            stream.push(rec.acc[:, i:i + 50], rec.gyr[:, i:i + 50], rec.mag[:, i:i + 50])
        stream.close()
    return [str(w.message) for w in caught if str(w.message).startswith("the stream's")]


def _when(said: list[str], kinds: tuple, sensors) -> str | None:
    """The stretch (its times) whose finding of one of `kinds` names every one of `sensors`."""
    for message in said:
        if any(k in message for k in kinds) and all(s in message for s in sensors):
            return message.split(":")[0].removeprefix("the stream's ")
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out seeds, comma-separated")
    ap.add_argument("--checks-s", default="10,20", help="stretch lengths, s, comma-separated")
    args = ap.parse_args()
    lengths = [float(s) for s in args.checks_s.split(",")]
    counts = {s: {"false": 0, "grasps": 0, "exchanged": 0, "late": 0, "turned": 0}
              for s in lengths}
    totals = {"recordings": 0, "grasps": 0, "exchanged": 0, "late": 0, "turned": 0}
    for seed in (int(s) for s in args.seeds.split(",")):
        config, calib, sensor_cal, hand = heldout_draw(seed)
        timed = sorted({s for pair in HINGES + CARRIED + RIGID for s in pair})
        phalanges = [s for s in calib.sensors if s.split("_")[-1] in ("proximal", "middle", "distal")]
        for n, (_, elbow, rec) in enumerate(free_trials(config, hand, durations=(30.0,))):
            rec = sensor_cal.apply(rec).subset(calib.sensors)
            joined = sorted(turn_ratios(rec, calib.model))  # the sensors a joint joins
            rng = np.random.default_rng([seed, n, 7])
            faults = [("exchanged", ("read as exchanged",), (a, b), _exchanged(rec, a, b))
                      for a, b in (rng.choice(joined, 2, replace=False) for _ in range(3))]
            faults += [("late", ("out of step",), (s,), delayed(rec, s, 2))
                       for s in rng.choice(timed, 3, replace=False)]
            faults += [("turned", ("read as turned", "beyond"), (s,),
                        _turned(rec, s, "half a turn about its z axis"))
                       for s in rng.choice(phalanges, 2, replace=False)]
            totals["recordings"] += 1
            for kind, _, _, _ in faults:
                totals[kind] += 1
            for length in lengths:
                clean = _said(calib, rec, length)
                counts[length]["false"] += bool(clean)
                told = []
                for kind, words, sensors, faulty in faults:
                    when = _when(_said(calib, faulty, length), words, sensors)
                    counts[length][kind] += when is not None
                    told.append(f"{kind} {'/'.join(sensors)}: {when or 'NOT TOLD'}")
                print(f"seed {seed} elbow {elbow}, stretches of {length:g} s: as recorded "
                      f"{'WARNED: ' + clean[0][:160] if clean else 'nothing said'}", flush=True)
                for line in told:
                    print(f"    {line}", flush=True)
        for label, rec in grasp_reaches(config, hand):   # as recorded: false alarms only
            rec = sensor_cal.apply(rec).subset(calib.sensors)
            totals["grasps"] += 1
            for length in lengths:
                clean = _said(calib, rec, length)
                counts[length]["grasps"] += bool(clean)
                print(f"seed {seed} {label} ({rec.duration_s:.0f} s), stretches of {length:g} s: "
                      f"{'WARNED: ' + clean[0][:160] if clean else 'nothing said'}", flush=True)
    for length in lengths:
        c = counts[length]
        print(f"stretches of {length:g} s: false alarms {c['false']} of {totals['recordings']} "
              f"(grasp reaches {c['grasps']} of {totals['grasps']}); "
              f"told: exchanged {c['exchanged']} of {totals['exchanged']}, 20 ms late "
              f"{c['late']} of {totals['late']}, turned {c['turned']} of {totals['turned']}")
    fields = [f"{k}_{s:g}={v}" for s in lengths for k, v in
              (("false_alarms", counts[s]["false"]), ("grasp_false_alarms", counts[s]["grasps"]),
               ("told_exchanged", counts[s]["exchanged"]),
               ("told_late", counts[s]["late"]), ("told_turned", counts[s]["turned"]))]
    print(" ".join(fields + [f"{k}={v}" for k, v in totals.items()]))


if __name__ == "__main__":
    main()
