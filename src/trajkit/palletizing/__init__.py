"""Palletizing: layer patterns, scenarios, cycle planners, verification, reports.

Quick start::

    from trajkit.palletizing import seed_scenario, plan_cycle, verify_plan
    sc = seed_scenario()
    plan = plan_cycle(sc, "optimal")     # or "merged", "ptp"; "cell" with a cell
    verify_plan(plan).raise_if_failed()
    print(plan.total_s, plan.per_box_s)
"""

from ._crossing import time_at_position
from .cell import Cell, GripperVolume, Obstacle
from .cellcheck import CellFinding, CellReport, check_cell
from .cellplan import CellTrip, plan_cycle_cell
from .optimal import (
    OptimalTrip,
    clearance_window,
    plan_cycle_optimal,
    plan_trip_optimal,
    trip_lower_bound,
)
from .patterns import (
    ALTERNATE_MODES,
    PATTERN_NAMES,
    BoxSize,
    LayerPattern,
    StackPattern,
    check_layer_fit,
    column_layer,
    interlock_layer,
    make_pattern,
    pinwheel_layer,
    seed_layer,
)
from .planners import (
    PLANNERS,
    CyclePlan,
    TripPlan,
    merged_trip_times,
    optimal_zmax,
    plan_cycle,
    plan_trip_merged,
    plan_trip_ptp,
    register_planner,
)
from .report import PAPER_TABLE1, summarize, table_rows
from .scenario import PalletScenario, TripSpec, seed_scenario
from .timeline import Piece, Timeline, TimelineSample
from .verify import PlanVerificationError, VerificationReport, verify_plan

__all__ = [
    "ALTERNATE_MODES", "PATTERN_NAMES", "BoxSize", "LayerPattern", "StackPattern",
    "check_layer_fit", "column_layer", "interlock_layer", "make_pattern", "pinwheel_layer",
    "seed_layer",
    "PLANNERS", "CyclePlan", "TripPlan", "merged_trip_times", "optimal_zmax", "plan_cycle",
    "plan_trip_merged", "plan_trip_ptp", "register_planner",
    "OptimalTrip", "clearance_window", "plan_cycle_optimal", "plan_trip_optimal",
    "trip_lower_bound",
    "Cell", "GripperVolume", "Obstacle", "CellFinding", "CellReport", "check_cell",
    "CellTrip", "plan_cycle_cell",
    "PAPER_TABLE1", "summarize", "table_rows",
    "PalletScenario", "TripSpec", "seed_scenario",
    "Piece", "Timeline", "TimelineSample",
    "PlanVerificationError", "VerificationReport", "verify_plan",
    "time_at_position",
]
