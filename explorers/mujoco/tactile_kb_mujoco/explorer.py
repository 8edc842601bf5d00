"""The ``mujoco`` explorer: the shared servo controller driving a :class:`MujocoWorld`.

Registered in the entry-point group ``tactile_kb.explorers`` as ``mujoco``, so
``tactile_kb.explorers.get_explorer("mujoco")`` and ``tactile-kb classify ... --explorer
mujoco`` find it once this distribution is installed.

Examples
--------
>>> from tactile_kb.explorers import get_explorer
>>> explorer = get_explorer("mujoco")
>>> type(explorer).__name__, explorer.name
('MujocoExplorer', 'mujoco')
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from tactile_kb.explorers import WorldExplorer
from tactile_kb.finger import Finger
from tactile_kb_mujoco.scene import SceneOptions
from tactile_kb_mujoco.world import MujocoWorld

if TYPE_CHECKING:
    import trimesh

    from tactile_kb.completion import CompletionParams
    from tactile_kb.servo import ServoParams

__all__ = ["MujocoExplorer"]


class MujocoExplorer(WorldExplorer):
    """Explore an object in a MuJoCo simulation with the same controller as ``stepper``.

    Parameters
    ----------
    params
        Servo parameters (:class:`tactile_kb.servo.ServoParams`); the defaults suit 2–30 cm
        objects.
    speed
        Motor speed along a motion, m/s.
    press
        How far the set-points go into a followed surface during a slide, metres.
    threshold
        Touch-sensor force above which a sensor is ON, newtons.
    options
        The scene's physical parameters (:class:`~tactile_kb_mujoco.scene.SceneOptions`).
    completion
        Budget of the model-driven completion (:class:`tactile_kb.completion.CompletionParams`).
    """

    name = "mujoco"

    def __init__(
        self,
        params: ServoParams | None = None,
        *,
        speed: float = 0.25,
        press: float = 1e-4,
        threshold: float = 0.0,
        options: SceneOptions | None = None,
        completion: CompletionParams | None = None,
    ) -> None:
        super().__init__(params, completion=completion)
        self.speed = speed
        self.press = press
        self.threshold = threshold
        self.options = options

    def make_world(
        self, mesh: trimesh.Trimesh, finger: Finger, *, seed: int | None, noise: float
    ) -> MujocoWorld:
        """The MuJoCo world of ``mesh`` sensed with ``finger``."""
        return MujocoWorld(
            mesh,
            finger,
            noise=noise,
            seed=seed,
            speed=self.speed,
            press=self.press,
            threshold=self.threshold,
            options=self.options,
        )
