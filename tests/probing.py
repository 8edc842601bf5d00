"""A completer for the exploration tests: it asks for one given probe, then ends."""

from __future__ import annotations

from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.servo import Ending, Probe


class OneProbe:
    """A :class:`~tactile_kb.touch.servo.Completer` that asks for ``probe`` once, then ends."""

    def __init__(self, probe: Probe) -> None:
        self.probe = probe
        self.asked = False

    def next_probe(
        self, record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe | Ending:
        del record, last
        if self.asked:
            return Ending("closed", "one probe asked")
        self.asked = True
        return self.probe
