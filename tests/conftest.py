import os

# Headless rendering for the whole suite (the library sets the same default).
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")
