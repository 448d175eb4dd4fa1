"""state_machine_controller's core, as ``closed_loop.nodes.state_machine_controller`` drives it."""
from closed_loop.control import state_machine
from closed_loop.controllers.front import FrontController
from closed_loop.control.decisions import input_problem


class StateMachineController(FrontController):
    name = 'state_machine_controller'
    settings_class = state_machine.BackUpSettings

    def __init__(self, settings, context):
        FrontController.__init__(self, settings, context)
        self.machine = state_machine.BackUpStateMachine(settings)
        self.mode = self.machine.state.name

    def react_now(self, reading, age_s):
        return state_machine.react_now(self.machine.state, reading, self.settings)

    def decide(self, now_s):
        if input_problem(self.reading, self.age_s(now_s), self.settings.scan_timeout) is not None:
            return 0.0, 0.0         # stopped, the machine on hold
        state, linear_x = self.machine.update(self.reading.distance_m, now_s)
        self.mode = state.name
        return linear_x, 0.0
