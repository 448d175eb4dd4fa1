"""state_machine_controller: the lesson's EXPLORING / BACKING_UP behaviour, on the host's clock.

It explores forward at ``explore_speed`` and, when the nearest obstacle ahead is closer than
``trigger_distance``, backs up at ``backup_speed`` for ``backup_duration`` s, then explores again
(``closed_loop.control.state_machine``); a reading that triggers backing up is acted on at once. While the
reading is missing, stale, malformed or all-invalid it sends zero and holds the machine where it is. Its
mode is the state.
"""
from closed_loop.control import state_machine
from closed_loop.control.decisions import input_problem
from closed_loop.controllers import STOP
from closed_loop.controllers.front import FrontController


class StateMachineController(FrontController):
    name = 'state_machine_controller'
    settings_class = state_machine.BackUpSettings

    def __init__(self, settings, context, *extra_settings):
        FrontController.__init__(self, settings, context)
        self.machine = state_machine.BackUpStateMachine(settings, on_transition=self._on_transition)
        self.enter(self.machine.state.name, None, 'start')

    def reconfigure(self, settings):
        FrontController.reconfigure(self, settings)
        self.machine.reconfigure(settings)

    def react_now(self, reading, age_s):
        return state_machine.react_now(self.machine.state, reading, self.settings)

    def decide(self, now_s):
        problem = input_problem(self.reading, self.age_s(now_s), self.settings.scan_timeout)
        if problem is not None:
            self.fault = '%s on hold: %s' % (self.machine.state.name, problem)
            return STOP
        self.fault = None
        _state, linear_x = self.machine.update(self.reading.distance_m, now_s)
        return linear_x, 0.0

    def _on_transition(self, old, new, now_s):
        self.enter(new.name, now_s, 'front obstacle %.2f m' % self.reading.distance_m)
