"""Robot motion programs: PTP, LIN, CIRC and WAIT on a robot model, with blending.

``run_motions(robot, motions, start)`` plans a list of motions
(:mod:`trajkit.robot.motion`) and returns a :class:`RobotRun` that samples
at any period (IK at every Cartesian sample) and summarises the program
(time, slow-downs, limit usage).
"""

from ._cartesian import Slowdown
from .execute import RobotRun, RobotSamples, Segment, run_motions
from .motion import CartesianTarget, Circ, JointTarget, Lin, Ptp, Wait

__all__ = ["run_motions", "RobotRun", "RobotSamples", "Segment", "Slowdown",
           "Ptp", "Lin", "Circ", "Wait", "JointTarget", "CartesianTarget"]
