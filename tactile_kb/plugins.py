"""Name → implementation registries with lazy loading, entry points and install hints.

Explorers (group ``tactile_kb.explorers``) and feature extractors (group
``tactile_kb.features.builtin``) are found the same way: third parties declare an entry point in their
``pyproject.toml``, and the built-ins register through the very same mechanism. An entry point
names one plugin, or a *provider*: a mapping ``{name: plugin}`` that contributes several.

Asking for a plugin that cannot load raises :class:`~tactile_kb.errors.PluginUnavailableError`
carrying its install hint; nothing ever falls back silently to another implementation. A
broken third-party entry point is logged and skipped during discovery.

Examples
--------
>>> reg: Registry[int] = Registry("example.group", "number")
>>> reg.register("one", 1)
>>> reg.get("one")
1
>>> reg.register_hint("two", "pip install two")
>>> reg.get("two")
Traceback (most recent call last):
...
tactile_kb.errors.PluginUnavailableError: 'two' cannot load (not installed); install it with: pip install two
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Generic, TypeVar

from tactile_kb.errors import PluginError, PluginUnavailableError

__all__ = ["PluginStatus", "Registry"]

log = logging.getLogger(__name__)

T = TypeVar("T")


@dataclass(frozen=True)
class PluginStatus:
    """Whether a plugin loads: ``ok``, else the ``reason`` and the install ``hint``."""

    name: str
    ok: bool
    source: str
    reason: str = ""
    hint: str = ""


class Registry(Generic[T]):
    """A registry of plugins of one kind, filled from code and from an entry-point group."""

    def __init__(self, group: str, kind: str, check: Callable[[Any], bool] | None = None) -> None:
        self.group = group
        self.kind = kind
        self._check = check
        self._loaded: dict[str, T] = {}
        self._lazy: dict[str, str] = {}  # name -> "module:attr"
        self._sources: dict[str, str] = {}
        self._hints: dict[str, str] = {}
        self._failed: dict[str, str] = {}
        self._discovered = False

    # registration -----------------------------------------------------------------------------
    def register(self, name: str, plugin: T | str, *, source: str = "code") -> None:
        """Register ``plugin`` (an object, or a lazy ``"module:attr"`` reference) as ``name``."""
        if isinstance(plugin, str):
            self._lazy[name] = plugin
            self._loaded.pop(name, None)
        else:
            self._accept(name, plugin)
            self._loaded[name] = plugin
            self._lazy.pop(name, None)
        self._failed.pop(name, None)
        self._sources[name] = source

    def register_hint(self, name: str, hint: str) -> None:
        """Record how to install ``name``, a plugin that may not be installed."""
        self._hints[name] = hint

    def _accept(self, name: str, plugin: Any) -> None:
        if self._check is not None and not self._check(plugin):
            raise PluginError(f"{self.kind} {name!r} is not a valid {self.kind}: {plugin!r}")

    # discovery --------------------------------------------------------------------------------
    def _discover(self) -> None:
        if self._discovered:
            return
        self._discovered = True
        for ep in entry_points(group=self.group):
            if ep.name in self._loaded or ep.name in self._lazy:
                continue
            self._from_entry_point(ep)

    def _from_entry_point(self, ep: EntryPoint) -> None:
        dist = ep.dist.name if ep.dist is not None else "?"
        try:
            obj = ep.load()
        except Exception as exc:  # a broken third-party plugin must not break discovery
            log.warning(
                "skipping %s %r from %s: %s: %s", self.kind, ep.name, dist, type(exc).__name__, exc
            )
            self._failed[ep.name] = f"{type(exc).__name__}: {exc}"
            self._sources[ep.name] = f"entry point of {dist}"
            return
        items: Mapping[str, Any] = obj if isinstance(obj, Mapping) else {ep.name: obj}
        for name, plugin in items.items():
            try:
                self._accept(name, plugin)
            except PluginError as exc:
                log.warning("skipping %s", exc)
                self._failed[name] = str(exc)
                continue
            self._loaded.setdefault(name, plugin)
            self._sources.setdefault(name, f"entry point of {dist}")

    # lookup -----------------------------------------------------------------------------------
    def get(self, name: str) -> T:
        """The plugin called ``name``; raises with an install hint if it cannot load."""
        self._discover()
        if name in self._loaded:
            return self._loaded[name]
        if name in self._lazy:
            ref = self._lazy[name]
            module, _, attr = ref.partition(":")
            try:
                obj: Any = importlib.import_module(module)
                for part in attr.split(".") if attr else []:
                    obj = getattr(obj, part)
            except ImportError as exc:
                hint = self._hints.get(name, f"install the package that provides {module}")
                raise PluginUnavailableError(name, hint, f"{exc}") from None
            self._accept(name, obj)
            self._loaded[name] = obj
            return obj  # type: ignore[no-any-return]
        if name in self._failed:
            hint = self._hints.get(name, "reinstall the plugin's distribution")
            raise PluginUnavailableError(name, hint, self._failed[name])
        if name in self._hints:
            raise PluginUnavailableError(name, self._hints[name], "not installed")
        known = ", ".join(self.names()) or "none"
        raise PluginError(f"unknown {self.kind} {name!r} (known: {known})")

    def names(self) -> list[str]:
        """Names of every registered plugin (loaded or lazy), sorted."""
        self._discover()
        return sorted(set(self._loaded) | set(self._lazy))

    def status(self) -> list[PluginStatus]:
        """Every known plugin, including hinted and failed ones, and whether it loads."""
        self._discover()
        out = []
        for name in sorted(
            set(self._loaded) | set(self._lazy) | set(self._hints) | set(self._failed)
        ):
            source = self._sources.get(name, "not installed")
            try:
                self.get(name)
            except PluginUnavailableError as exc:
                out.append(PluginStatus(name, False, source, exc.reason, exc.hint))
            else:
                out.append(PluginStatus(name, True, source))
        return out

    def available(self) -> list[str]:
        """Names of the plugins that load."""
        return [s.name for s in self.status() if s.ok]
