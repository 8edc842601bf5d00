"""tactile-kb-mujoco: the MuJoCo explorer plugin of tactile_kb.

The finger of :mod:`tactile_kb.touch.finger` becomes a MuJoCo body on three motor-driven slide
joints with one touch sensor per tactile sensor; the object becomes fixed convex geoms; the
shared servo controller of :mod:`tactile_kb.touch.servo` drives it and fills the same
:class:`~tactile_kb.record.ExplorationRecord` as the analytic ``stepper``.
"""

from __future__ import annotations

from tactile_kb_mujoco.explorer import MujocoExplorer
from tactile_kb_mujoco.parts import Concavity, ConvexPart, convex_parts, felt_concavity
from tactile_kb_mujoco.scene import SceneOptions, scene_xml
from tactile_kb_mujoco.world import MujocoWorld

__version__ = "0.1.0"

__all__ = [
    "Concavity",
    "ConvexPart",
    "MujocoExplorer",
    "MujocoWorld",
    "SceneOptions",
    "__version__",
    "convex_parts",
    "felt_concavity",
    "scene_xml",
]
