"""The ``mujoco`` explorer: the shared servo controller driving a :class:`MujocoWorld`.

Registered in the entry-point group ``tactile_kb.explorers`` as ``mujoco``, so
``tactile_kb.touch.explorers.get_explorer("mujoco")`` and ``tactile-kb classify ... --explorer
mujoco`` find it once this distribution is installed.

Examples
--------
>>> from tactile_kb.touch.explorers import get_explorer
>>> explorer = get_explorer("mujoco")
>>> type(explorer).__name__, explorer.name
('MujocoExplorer', 'mujoco')
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from tactile_kb.touch.explorers import WorldExplorer
from tactile_kb.touch.finger import Finger
from tactile_kb_mujoco.scene import SceneOptions
from tactile_kb_mujoco.world import MujocoWorld

if TYPE_CHECKING:
    from collections.abc import Callable

    import trimesh

    from tactile_kb.touch.servo import Completer, ServoParams

__all__ = ["MujocoExplorer"]


class MujocoExplorer(WorldExplorer):
    """Explore an object in a MuJoCo simulation with the same controller as ``stepper``.

    Parameters
    ----------
    params
        Servo parameters (:class:`tactile_kb.touch.servo.ServoParams`); the defaults suit 2–30 cm
        objects.
    speed
        Motor speed along a motion, m/s.
    press
        How far the set-points go into a followed surface during a slide, metres.
    threshold
        Touch-sensor force above which a sensor is ON, newtons.
    options
        The scene's physical parameters (:class:`~tactile_kb_mujoco.scene.SceneOptions`).
    dropout, false_fire
        Sensor fault probabilities, added to the simulation by
        :class:`tactile_kb.touch.sensors.FaultySensors` as in every world.
    completer
        Makes the completer of one exploration (see
        :class:`~tactile_kb.touch.explorers.WorldExplorer`).
    concavity_tol
        How deep (metres, beyond the surface's roughness) the tip may reach under a mesh's
        convex hull for the mesh to be collided as that hull rather than decomposed by CoACD
        (:class:`~tactile_kb_mujoco.world.MujocoWorld`); default one tip radius, 0 always
        decomposes.
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
        dropout: float = 0.0,
        false_fire: float = 0.0,
        completer: Callable[[], Completer] | None = None,
        concavity_tol: float | None = None,
    ) -> None:
        super().__init__(params, completer=completer, dropout=dropout, false_fire=false_fire)
        self.speed = speed
        self.press = press
        self.threshold = threshold
        self.options = options
        self.concavity_tol = concavity_tol

    def make_world(self, mesh: trimesh.Trimesh, finger: Finger, *, seed: int | None) -> MujocoWorld:
        """The MuJoCo world of ``mesh`` sensed with ``finger`` (ideal; the session adds the
        sensor faults and the encoder noise)."""
        del seed  # the simulation is deterministic
        return MujocoWorld(
            mesh,
            finger,
            speed=self.speed,
            press=self.press,
            threshold=self.threshold,
            options=self.options,
            concavity_tol=self.concavity_tol,
        )
