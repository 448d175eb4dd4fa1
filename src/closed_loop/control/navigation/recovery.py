"""Recovering after ``stuck_timeout`` without progress (``navigator.Navigator``'s RECOVERING): back up where
the scan sees the rear clear; while turning in place is not safe, back out along the way it came
(``trail``, what the map says is clear), or where that move is not safe or there is no trail, straight back
or on a backing arc, up to BACKOUT_M from where the recovery began and BACKOUT_S from its start; then turn in
place toward the side not tried last time. Every move is checked by ``move_check.MoveCheck`` (the package's one
rule). Free of ROS.
"""
import math

from closed_loop.control.loop import lasted
from closed_loop.control.navigation.trail import TRAIL_LOOKBACK_M, TRAIL_STEP_M, back_toward, rear_seen

#: Recovery: back up at this speed for this long (if the scan sees the rear clear); while turning in place is
#: not safe, back out along the way it came (``closed_loop.control.navigation.trail``, what the map says is clear), or
#: where that move is not safe or there is no trail, straight back or on a backing arc (each move checked
#: against the scan and what it remembers), up to BACKOUT_M from where the recovery began and BACKOUT_S from
#: its start; then turn in place at this rate for this long toward the side
#: not tried last time (if turning is safe).
BACKUP_SPEED_MPS = 0.15
BACKUP_S = 1.0
BACKOUT_M = 0.6
BACKOUT_S = 8.0
#: Where neither the way it came nor straight back keeps the margin, a backing arc at this turn rate (rad/s).
BACKING_ARC_RADPS = 0.4
RECOVERY_TURN_RADPS = 0.8
RECOVERY_TURN_S = 2.0


class Recovery:
    """One recovery, begun at ``started_s`` with the robot at ``pose`` (odom), turning toward ``side`` (+1 left,
    -1 right) once it has room; ``trail``: the way it came (``trail.Trail``)."""

    def __init__(self, started_s, side, pose, trail):
        self.started_s, self.side, self.turn_s = started_s, side, None
        self.start_xy = pose[:2]
        self.end = trail.back(BACKOUT_M) if len(trail) > 1 else None    # where backing out along the trail ends

    def command(self, now_s, pose, sit, safe, trail, s):
        """(v, w, why) now, or None when it is over. ``sit``: the decision's ``situation.Situation``; ``safe(v,
        w, seconds)``: the move check; ``s``: the navigator's settings."""
        elapsed = now_s - self.started_s
        turn = self.side * RECOVERY_TURN_RADPS
        if self.turn_s is None:
            if not lasted(elapsed, BACKUP_S) and rear_seen(sit.scan, sit.laser_pose):
                if safe(-BACKUP_SPEED_MPS, 0.0, BACKUP_S - elapsed):
                    return -BACKUP_SPEED_MPS, 0.0, 'backing up'
            elif not lasted(elapsed, BACKOUT_S) and math.hypot(self.start_xy[0] - pose[0],
                                                               self.start_xy[1] - pose[1]) < BACKOUT_M \
                    and not safe(0.0, turn, min(s.horizon, RECOVERY_TURN_S)):
                # No room to turn: back out the way it came, or else straight back or on a backing arc.
                moves = [(-BACKUP_SPEED_MPS, 0.0, 'backing straight out')] + [
                    (-BACKUP_SPEED_MPS, side * BACKING_ARC_RADPS, 'backing out on an arc')
                    for side in (self.side, -self.side)]
                if self.end is not None and math.hypot(self.end[0] - pose[0], self.end[1] - pose[1]) > TRAIL_STEP_M:
                    trail.drop_behind(pose[0], pose[1])
                    moves.insert(0, back_toward(pose, trail.back(TRAIL_LOOKBACK_M), BACKUP_SPEED_MPS,
                                                s.max_yaw_rate) + ('backing out the way it came',))
                for v, w, what in moves:
                    if safe(v, w, BACKUP_S):
                        return v, w, what + ': no room to turn here'
            self.turn_s = now_s
        if not lasted(now_s - self.turn_s, RECOVERY_TURN_S) and safe(0.0, turn, min(s.horizon, RECOVERY_TURN_S -
                                                                                 (now_s - self.turn_s))):
            return 0.0, turn, 'turning to try the other side'
        return None
