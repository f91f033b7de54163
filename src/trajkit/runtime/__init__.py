"""Runtime: streaming interpolator, step pulses, safety monitors, servo simulation.

See ``docs/runtime.md`` for the API summary. The math kernels here
(:func:`brake_profile`, :class:`ServoBank`, :class:`PulseAxis`) take and
return numbers/arrays; :class:`Streamer` runs them once per control period.
"""

from ._brake import BrakeProfile, brake_profile, stop_position
from ._warmup import WARM_UP_PARTS, warm_up, warm_up_pending
from .pulses import PulseAxis, PulseRateFault, edge_times, pulse_count, pulse_counts
from .safety import QUANTITIES, REACTIONS, RuntimeFault, SafetyConfig
from .servo import ServoBank, ServoParams, cao2012_servo
from .simulate import MotionTiming, SimulationReport, simulate
from .source import ProgramSource, as_source
from .streamer import STATES, RuntimeEvent, Setpoint, Streamer

__all__ = [
    "QUANTITIES",
    "REACTIONS",
    "STATES",
    "WARM_UP_PARTS",
    "BrakeProfile",
    "MotionTiming",
    "ProgramSource",
    "PulseAxis",
    "PulseRateFault",
    "RuntimeEvent",
    "RuntimeFault",
    "SafetyConfig",
    "ServoBank",
    "ServoParams",
    "Setpoint",
    "SimulationReport",
    "Streamer",
    "as_source",
    "brake_profile",
    "edge_times",
    "pulse_count",
    "pulse_counts",
    "cao2012_servo",
    "simulate",
    "stop_position",
    "warm_up",
    "warm_up_pending",
]
