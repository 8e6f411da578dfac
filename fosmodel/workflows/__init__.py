"""Workflows: the steps below (noise, study, loop) put together over a whole record.

The six-axis workflow (every axis's Allan noise, model-order study and residual loop) and its
report, fleets of records (each record one task, here or on Dask, resumable), and thermal
calibrations (every axis's bias against temperature, judged out of sample, for PX4 and
ArduPilot).

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
    from .tempcal import AxisGroup, TempcalConfig, TempcalResult, TempSession, run_tempcal
    from .tempcal_px4 import px4_fit
    from .tempcal_records import tempcal_groups
    from .tempcal_report import write_tempcal
else:
    __getattr__, __dir__ = attach(__name__, {
        "fleet": ("FleetResult", "run_fleet"),
        "fleet_record": ("FleetConfig", "MARKER", "record_name"),
        "imu": ("AxisResult", "ImuConfig", "ImuResult", "run_imu"),
        "imu_report": ("write_imu_report",),
        "tempcal": ("AxisGroup", "TempSession", "TempcalConfig", "TempcalResult", "run_tempcal"),
        "tempcal_px4": ("px4_fit",),
        "tempcal_records": ("tempcal_groups",),
        "tempcal_report": ("write_tempcal",),
    })

__all__ = ["MARKER", "AxisGroup", "AxisResult", "FleetConfig", "FleetResult", "ImuConfig",
           "ImuResult", "TempSession", "TempcalConfig", "TempcalResult", "px4_fit", "record_name",
           "run_fleet", "run_imu", "run_tempcal", "tempcal_groups", "write_imu_report",
           "write_tempcal"]
