"""stop_on_obstacle: the lesson's stop / slow / cruise controller, failing safe.

It drives forward at a speed set by the nearest obstacle in the front sector: ``cruise_speed`` when clear,
``slow_speed`` under ``slow_distance``, zero under ``stop_distance``, leaving a zone only ``hysteresis`` past
its limit (``closed_loop.control.decisions``). A reading that is missing, stale (older than
``scan_timeout``), malformed or all-invalid means stop. A reading that would make things more dangerous
is acted on at once, unless ``react_immediately`` is false: then only the timer acts (the lesson's design,
up to one period later). Its mode is the zone: CLEAR, SLOW or STOP.
"""
from closed_loop.control import decisions
from closed_loop.controllers.front import FrontController


class StopOnObstacle(FrontController):
    name = 'stop_on_obstacle'
    settings_class = decisions.StopSettings
    warn_modes = (decisions.Zone.STOP.name,)

    def __init__(self, settings, context, *extra_settings):
        FrontController.__init__(self, settings, context)
        self.zone = None

    def react_now(self, reading, age_s):
        """:func:`closed_loop.control.decisions.react_now`: the first decision (no zone yet: the end of
        start-up, before which nothing was sent) and, unless ``react_immediately`` is false, new danger."""
        return decisions.react_now(reading, age_s, self.zone, self.settings)

    def decide(self, now_s):
        decision = decisions.decide(self.reading, self.age_s(now_s), self.zone, self.settings)
        # Before the first scan arrives there is nothing to report yet: stopped, with no zone.
        return self._take(decision, now_s, report=not (decision.fault and not self.scans_seen))

    def on_silence(self, now_s, silent_s):
        FrontController.on_silence(self, now_s, silent_s)
        return self._take(decisions.stop(self.fault), now_s)

    def _take(self, decision, now_s, report=True):
        self.fault = decision.reason if decision.fault else None
        if report:
            self.zone = decision.zone
            self.enter(decision.zone.name, now_s, decision.reason)
        return decision.linear_x, 0.0
