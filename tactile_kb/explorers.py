"""Explorers are plugins: the interface, the registry, and a base class for world-based ones.

An *explorer* turns an object (a mesh or a mesh file) and a finger into an
:class:`~tactile_kb.record.ExplorationRecord`. Explorers register under the entry-point group
``tactile_kb.explorers``; the built-in ``stepper`` (:class:`tactile_kb.stepper.StepperExplorer`)
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

A physics-based explorer only has to build a :class:`~tactile_kb.world.World`: subclass
:class:`WorldExplorer` and implement :meth:`WorldExplorer.make_world`; the shared servo
controller (:mod:`tactile_kb.servo`) does the rest and fills the same record type.

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
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

from tactile_kb.errors import PluginError, UsageError
from tactile_kb.finger import Finger, load_finger
from tactile_kb.objects import NOTES_KEY, ObjectLike, check_thickness, load_object, object_name
from tactile_kb.plugins import Registry
from tactile_kb.record import ExplorationRecord

if TYPE_CHECKING:
    import trimesh

    from tactile_kb.completion import CompletionParams
    from tactile_kb.servo import Controller, ServoParams
    from tactile_kb.world import World

__all__ = [
    "GOALS",
    "MUJOCO_HINT",
    "ExplorationSession",
    "Explorer",
    "Goal",
    "ServoSession",
    "WorldExplorer",
    "available_explorers",
    "explorer_registry",
    "get_explorer",
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


@runtime_checkable
class Explorer(Protocol):
    """What every explorer provides.

    ``finger`` is a :class:`~tactile_kb.finger.Finger`, a built-in layout name (``"4"``,
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
    """An :class:`ExplorationSession` over the shared controller (:class:`tactile_kb.servo.Controller`)."""

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
    """Base of explorers that drive the shared servo controller in a :class:`~tactile_kb.world.World`.

    Subclasses set :attr:`name` and implement :meth:`make_world`. ``params`` are the servo
    parameters (:class:`tactile_kb.servo.ServoParams`, default when ``None``) and
    ``completion`` the budget of the model-driven completion after contour following
    (:class:`tactile_kb.completion.CompletionParams`, default when ``None``); like a
    scikit-learn estimator, ``__init__`` only stores them.
    """

    name: str = ""

    def __init__(
        self, params: ServoParams | None = None, *, completion: CompletionParams | None = None
    ) -> None:
        self.params = params
        self.completion = completion

    @abc.abstractmethod
    def make_world(
        self, mesh: trimesh.Trimesh, finger: Finger, *, seed: int | None, noise: float
    ) -> World:
        """The world in which ``mesh`` (resting on z = 0, a private copy) is sensed by ``finger``."""

    def session(
        self,
        obj: ObjectLike,
        *,
        finger: Finger | str = "33",
        seed: int | None = 0,
        noise: float = 0.0,
    ) -> ServoSession:
        """Start a lazy exploration of ``obj`` (nothing is explored before :meth:`ServoSession.advance`)."""
        from tactile_kb.completion import ModelCompleter
        from tactile_kb.servo import Controller, ServoParams

        if noise < 0:
            raise UsageError(f"noise must be ≥ 0 metres, got {noise}")
        if seed is not None and (not isinstance(seed, int) or seed < 0):
            raise UsageError(f"seed must be a whole number ≥ 0 or None, got {seed!r}")
        mesh = load_object(obj)
        f = load_finger(finger)
        check_thickness(mesh, f.radius, name=object_name(obj))
        world = self.make_world(mesh, f, seed=seed, noise=noise)
        controller = Controller(
            world,
            self.params or ServoParams(),
            explorer=self.name,
            object_name=object_name(obj),
            seed=seed,
            extra_params={"noise": float(noise)},
            completer=ModelCompleter(self.completion),
        )
        controller.notes.extend(str(n) for n in mesh.metadata.get(NOTES_KEY, []))
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
        return f"{type(self).__name__}(params={self.params!r})"


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
            "stepper", "tactile_kb.stepper:StepperExplorer", source="built-in"
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
