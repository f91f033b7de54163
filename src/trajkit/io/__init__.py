"""Job and program files (YAML/JSON), validated at the boundary; units named in fields."""

from .pallet_job import (
    PalletJob,
    load_job,
    parse_job,
    scenario_from_job,
    seed_cell_job_path,
    seed_job_path,
)

__all__ = ["PalletJob", "load_job", "parse_job", "scenario_from_job", "seed_job_path",
           "seed_cell_job_path"]
