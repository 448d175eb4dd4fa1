"""The reactive navigator, stage by stage. One decision (``navigator.Navigator.update``) runs down this list,
and the first stage that has a command gives it:

1. ``navigator``      what it is doing (seeking, avoiding, recovering, reached, failed), its progress timers;
2. ``memory``, ``trail``  what it remembers of the scans (odom), and the way it came;
3. ``navigator``      recovering after a stall: back up, back out (``trail``), turn, each move checked by
                      ``move_check``;
4. ``escape``         out of a pocket: a plan for the footprint (``hybrid_kernel``), followed while it stays safe;
5. ``navigator``      the final approach to the goal, checked by ``move_check``;
6. ``window``         otherwise the dynamic window: the way round (``wavefront`` over ``wave_kernel``), the arc
                      candidates checked on a distance grid (``clearance_field``) and exactly where in doubt,
                      scored, the turn in place, following the way, and one period's step toward the choice.

What a decision knows travels in one object (``window.Situation``). Every "is this move safe?" is
``closed_loop.control.safety``'s one rule on its one predictor, below all of them (the guard asks it too).

Free of ROS and of the simulator, like the rest of ``closed_loop.control``.
"""
