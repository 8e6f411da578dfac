"""Workflows: the steps below (noise, study, loop) put together over a whole record.

The six-axis workflow (every axis's Allan noise, model-order study and residual loop) and its
report, and fleets of records (each record one task, here or on Dask, resumable).

Imports every layer below it.  Its public names are imported on first use
(:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .fleet import FleetResult, run_fleet
    from .fleet_record import MARKER, FleetConfig, record_name
    from .imu import AxisResult, ImuConfig, ImuResult, run_imu
    from .imu_report import write_imu_report
else:
    __getattr__, __dir__ = attach(__name__, {
        "fleet": ("FleetResult", "run_fleet"),
        "fleet_record": ("FleetConfig", "MARKER", "record_name"),
        "imu": ("AxisResult", "ImuConfig", "ImuResult", "run_imu"),
        "imu_report": ("write_imu_report",),
    })

__all__ = ["MARKER", "AxisResult", "FleetConfig", "FleetResult", "ImuConfig", "ImuResult",
           "record_name", "run_fleet", "run_imu", "write_imu_report"]
