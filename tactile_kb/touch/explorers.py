"""Explorers are plugins: the interface, the registry, and a base class for world-based ones.

An *explorer* turns an object (a mesh or a mesh file) and a finger into an
:class:`~tactile_kb.record.ExplorationRecord`. Explorers register under the entry-point group
``tactile_kb.explorers``; the built-in ``stepper`` (:class:`tactile_kb.touch.stepper.StepperExplorer`)
joins the same way. An entry point may name an explorer class (instantiated with no
arguments), an instance, or a provider mapping ``{name: explorer}``.

* :func:`available_explorers` lists the explorers that load;
* :func:`get_explorer` accepts a name or an instance (so tests need no entry points); asking
  for one that cannot load raises :class:`~tactile_kb.errors.PluginUnavailableError` with its
  install hint (``"mujoco"``: ``pip install -e ./explorers/mujoco``); nothing falls back
  silently.

Exploration can be lazy: :meth:`Explorer.session` returns an :class:`ExplorationSession` that
is advanced to a goal (``"contact"``: the first touch; ``"layer"``: the first closed contour;
``"complete"``: the end) and resumed later, so a classifier can evaluate phase I after the
first contact and explore further only if it needs to.

A physics-based explorer only has to build a :class:`~tactile_kb.touch.world.World`: subclass
:class:`WorldExplorer` and implement :meth:`WorldExplorer.make_world`; the shared servo
controller (:mod:`tactile_kb.touch.servo`) does the rest and fills the same record type.

Examples
--------
>>> "stepper" in available_explorers()
True
>>> get_explorer("stepper").name
'stepper'
>>> get_explorer("mujoco-nope")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
tactile_kb.errors.PluginError: unknown explorer 'mujoco-nope' (known: ...)
"""

from __future__ import annotations

import abc
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

from tactile_kb.errors import PluginError, UsageError
from tactile_kb.objects import NOTES_KEY, ObjectLike, check_thickness, load_object, object_name
from tactile_kb.plugins import Registry
from tactile_kb.record import ExplorationRecord
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.touch.finger import Finger, layout_warnings, load_finger
from tactile_kb.touch.sensors import FaultySensors, check_fault_rates

if TYPE_CHECKING:
    import trimesh

    from tactile_kb.touch.servo import Completer, Controller, ServoParams
    from tactile_kb.touch.world import World

__all__ = [
    "GOALS",
    "MUJOCO_HINT",
    "NOISE_OBJECT_FRACTION",
    "NOISE_WARN_FRACTION",
    "ExplorationSession",
    "Explorer",
    "Goal",
    "ServoSession",
    "WorldExplorer",
    "available_explorers",
    "explorer_registry",
    "get_explorer",
    "noise_problem",
]

Goal = Literal["contact", "layer", "complete"]
GOALS: tuple[Goal, ...] = ("contact", "layer", "complete")

MUJOCO_HINT = "pip install -e ./explorers/mujoco (or pip install -e '.[mujoco]')"


@runtime_checkable
class ExplorationSession(Protocol):
    """An exploration in progress that can be advanced to a goal and resumed."""

    @property
    def done(self) -> bool:
        """Whether the exploration has run to its end."""
        ...

    @property
    def record(self) -> ExplorationRecord:
        """The record so far (``complete`` is False until :attr:`done`)."""
        ...

    def advance(self, goal: Goal = "complete") -> ExplorationRecord:
        """Explore until ``goal`` is reached (or the end); return the record so far."""
        ...


NOISE_WARN_FRACTION = DEFAULTS.explore.noise_warn_fraction
"""σ of the contact-position noise above this fraction of the tip radius is warned about: on
the 5 mm tip, σ ≥ 1.5 mm makes flat faces read as curved."""

NOISE_OBJECT_FRACTION = DEFAULTS.explore.noise_object_fraction
"""σ above this fraction of the object's thinnest extent is noted in the record."""


def noise_problem(noise: float, tip_radius: float) -> tuple[str, str]:
    """``(refusal, warning)`` for a contact-position noise σ (metres) on a tip of ``tip_radius``.

    A σ that is negative, not finite, or at least the tip radius is refused: a sensor on the
    tip cannot misplace a contact by more than the tip's own size. A σ above
    :data:`NOISE_WARN_FRACTION` of the radius is allowed with a warning.

    Examples
    --------
    >>> noise_problem(0.5, 0.005)[0]
    'σ must be less than the tip radius (5 mm); the value is in metres, e.g. 0.0005 for 0.5 mm'
    >>> noise_problem(0.0015, 0.005)[1]
    'large against the 5 mm tip: flat faces may read as curved and faces may be lost'
    """
    r = f"{tip_radius * 1000:.3g} mm"
    if not math.isfinite(noise) or noise < 0:
        return (f"σ must be a finite number ≥ 0 metres, got {noise!r}", "")
    if noise >= tip_radius:
        return (
            f"σ must be less than the tip radius ({r}); the value is in metres, "
            "e.g. 0.0005 for 0.5 mm",
            "",
        )
    if noise > current().explore.noise_warn_fraction * tip_radius:
        return (
            "",
            f"large against the {r} tip: flat faces may read as curved and faces may be lost",
        )
    return ("", "")


@runtime_checkable
class Explorer(Protocol):
    """What every explorer provides.

    ``finger`` is a :class:`~tactile_kb.touch.finger.Finger`, a built-in layout name (``"4"``,
    ``"33"``) or a layout YAML file; ``seed`` makes the run reproducible; ``noise`` is the σ
    (metres) of the contact-position noise.
    """

    name: str

    def session(
        self,
        obj: ObjectLike,
        *,
        finger: Finger | str = "33",
        seed: int | None = 0,
        noise: float = 0.0,
    ) -> ExplorationSession:
        """Start a lazy exploration of ``obj``."""
        ...

    def explore(
        self,
        obj: ObjectLike,
        *,
        finger: Finger | str = "33",
        seed: int | None = 0,
        noise: float = 0.0,
    ) -> ExplorationRecord:
        """Explore ``obj`` to the end and return the record."""
        ...


class ServoSession:
    """An :class:`ExplorationSession` over the shared controller (:class:`tactile_kb.touch.servo.Controller`)."""

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self._steps = controller.run()
        self._done = False
        self._reached: set[str] = set()

    @property
    def done(self) -> bool:
        """Whether the exploration has run to its end."""
        return self._done

    @property
    def record(self) -> ExplorationRecord:
        """The record so far."""
        return self.controller.record(complete=self._done)

    def advance(self, goal: Goal = "complete") -> ExplorationRecord:
        """Run the controller until ``goal`` ("contact", "layer" or "complete") is reached."""
        if goal not in GOALS:
            raise UsageError(f"unknown exploration goal {goal!r} (use one of {', '.join(GOALS)})")
        while not self._done and goal not in self._reached:
            try:
                mark = next(self._steps)
            except StopIteration:
                self._done = True
                break
            self._reached.add(mark)
            if mark == "complete":
                self._done = True
        return self.record


class WorldExplorer(abc.ABC):
    """Base of explorers that drive the shared servo controller in a :class:`~tactile_kb.touch.world.World`.

    Subclasses set :attr:`name` and implement :meth:`make_world`, which returns an *ideal*
    world: the session wraps it in :class:`~tactile_kb.touch.sensors.FaultySensors`, which adds
    the encoder noise (``noise``, given per exploration) and the sensor faults (``dropout``,
    ``false_fire``, given here), the same in every world. ``params`` are the servo parameters
    (:class:`tactile_kb.touch.servo.ServoParams`, default when ``None``). ``completer`` makes
    the :class:`~tactile_kb.touch.servo.Completer` of one exploration, which asks for probes
    after contour following (the model-driven completion,
    :class:`tactile_kb.completion.ModelCompleter`, which :func:`tactile_kb.classify` and the
    command line attach); without one the finger follows the paper's servo rules alone. Like a
    scikit-learn estimator, ``__init__`` only stores its parameters.
    """

    name: str = ""

    def __init__(
        self,
        params: ServoParams | None = None,
        *,
        completer: Callable[[], Completer] | None = None,
        dropout: float = 0.0,
        false_fire: float = 0.0,
    ) -> None:
        self.params = params
        self.completer = completer
        self.dropout = dropout
        self.false_fire = false_fire

    @abc.abstractmethod
    def make_world(self, mesh: trimesh.Trimesh, finger: Finger, *, seed: int | None) -> World:
        """The ideal world in which ``mesh`` (resting on z = 0, a private copy) is sensed by
        ``finger``; ``seed`` is for a world's own randomness, if it has any."""

    def session(
        self,
        obj: ObjectLike,
        *,
        finger: Finger | str = "33",
        seed: int | None = 0,
        noise: float = 0.0,
    ) -> ServoSession:
        """Start a lazy exploration of ``obj`` (nothing is explored before :meth:`ServoSession.advance`)."""
        from tactile_kb.touch.servo import Controller, ServoParams

        f = load_finger(finger)
        refused, warning = noise_problem(noise, f.radius)
        if refused:
            raise UsageError(f"noise σ = {noise:g} m: {refused}")
        check_fault_rates(noise=noise, dropout=self.dropout, false_fire=self.false_fire)
        if seed is not None and (not isinstance(seed, int) or seed < 0):
            raise UsageError(f"seed must be a whole number ≥ 0 or None, got {seed!r}")
        mesh = load_object(obj)
        check_thickness(mesh, f.radius, name=object_name(obj))
        notes = []
        dx, dy = mesh.metadata.get("moved_xy", (0.0, 0.0))
        if abs(dx) > 1e-6 or abs(dy) > 1e-6:
            notes.append(
                f"the mesh was moved ({dx * 1000:+.4g}, {dy * 1000:+.4g}) mm along x and y so "
                "that it lies in the workspace (its bounding box centred over the origin)"
            )
        moved = float(mesh.metadata.get("moved_z", 0.0))
        if abs(moved) > 1e-6:
            notes.append(
                f"the mesh was moved {moved * 1000:+.3g} mm along z so that it rests on the "
                "table (z = 0)"
            )
        notes += layout_warnings(f)
        if warning:
            notes.append(f"noise σ = {noise * 1000:.3g} mm: {warning}")
        smallest = float(min(mesh.extents))
        if noise > current().explore.noise_object_fraction * smallest:
            notes.append(
                f"noise σ = {noise * 1000:.3g} mm is large against the object "
                f"({smallest * 1000:.3g} mm at its thinnest): faces and edges may be misread"
            )
        world = FaultySensors(
            self.make_world(mesh, f, seed=seed),
            noise=noise,
            dropout=self.dropout,
            false_fire=self.false_fire,
            seed=seed,
        )
        controller = Controller(
            world,
            self.params or ServoParams(),
            explorer=self.name,
            object_name=object_name(obj),
            seed=seed,
            noise=float(noise),
            completer=None if self.completer is None else self.completer(),
        )
        controller.notes.extend(str(n) for n in mesh.metadata.get(NOTES_KEY, []))
        controller.notes.extend(notes)
        return ServoSession(controller)

    def explore(
        self,
        obj: ObjectLike,
        *,
        finger: Finger | str = "33",
        seed: int | None = 0,
        noise: float = 0.0,
    ) -> ExplorationRecord:
        """Explore ``obj`` to the end."""
        return self.session(obj, finger=finger, seed=seed, noise=noise).advance("complete")

    def __repr__(self) -> str:
        faults = "".join(
            f", {k}={v!r}"
            for k, v in (("dropout", self.dropout), ("false_fire", self.false_fire))
            if v
        )
        return f"{type(self).__name__}(params={self.params!r}{faults})"


def _is_explorer(obj: Any) -> bool:
    if isinstance(obj, type):
        return callable(getattr(obj, "explore", None)) and callable(getattr(obj, "session", None))
    return isinstance(obj, Explorer)


explorer_registry: Registry[Any] = Registry("tactile_kb.explorers", "explorer", check=_is_explorer)
"""The registry of explorers (entry-point group ``tactile_kb.explorers``)."""

explorer_registry.register_hint("mujoco", MUJOCO_HINT)


def _ensure_builtin() -> None:
    # The built-in normally arrives through its own entry point; a source checkout that is not
    # installed has none, so register the same reference lazily as a fallback for *discovery*.
    if "stepper" not in explorer_registry.names():
        explorer_registry.register(
            "stepper", "tactile_kb.touch.stepper:StepperExplorer", source="built-in"
        )


def available_explorers() -> list[str]:
    """Names of the explorers that load, sorted."""
    _ensure_builtin()
    return explorer_registry.available()


def get_explorer(explorer: str | Explorer) -> Explorer:
    """The explorer named ``explorer`` (an instance, a class is instantiated), or ``explorer`` itself.

    Raises
    ------
    PluginUnavailableError
        The explorer is known but cannot load; the message carries its install hint.
    PluginError
        Unknown name, or an object that is not an explorer.
    """
    if not isinstance(explorer, str):
        if not isinstance(explorer, Explorer):
            raise PluginError(f"{explorer!r} is not an explorer (it needs session() and explore())")
        return explorer
    _ensure_builtin()
    obj = explorer_registry.get(explorer)
    if isinstance(obj, type):
        try:
            inst = obj()
        except Exception as exc:
            raise PluginError(
                f"explorer {explorer!r} failed to start: {type(exc).__name__}: {exc}"
            ) from None
        if not getattr(inst, "name", ""):
            inst.name = explorer
        return inst  # type: ignore[no-any-return]
    return obj  # type: ignore[no-any-return]
