"""stop_on_obstacle's core, as ``closed_loop.nodes.stop_on_obstacle`` drives it."""
from closed_loop.control import decisions
from closed_loop.controllers.front import FrontController


class StopOnObstacle(FrontController):
    name = 'stop_on_obstacle'
    settings_class = decisions.StopSettings

    def __init__(self, settings, context):
        FrontController.__init__(self, settings, context)
        self.zone = None

    def react_now(self, reading, age_s):
        return decisions.react_now(reading, age_s, self.zone, self.settings)

    def decide(self, now_s):
        decision = decisions.decide(self.reading, self.age_s(now_s), self.zone, self.settings)
        if not (decision.fault and self.stamp_s is None and self.zone is None):
            self.zone = decision.zone       # the node, too, reports nothing before its first scan
            self.mode = decision.zone.name
        return decision.linear_x, 0.0
