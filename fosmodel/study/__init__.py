"""Model-order studies: the harness, its runners, reports and the temperature study.

The train / evaluate / predict harness, running its fits here or on a Dask cluster, the
study reports, and the temperature-chamber study.

Imports the layers below it; never :mod:`fosmodel.loop`.  Its public names are imported on
first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .distributed import connect_scheduler, local_client
    from .harness import StudyConfig, StudyPlan, StudyResult, plan_study
    from .report import level_table, order_figure, paper_table, study_table, write_study
    from .runner import run_studies, run_study
    from .temperature import (
        TableModel,
        concatenate_plateaus,
        global_models,
        held_out_comparison,
        segment_noise,
        segment_table,
        temperature_inputs,
        temperature_segments,
        term_standard_errors,
    )
else:
    __getattr__, __dir__ = attach(__name__, {
        "distributed": ("connect_scheduler", "local_client"),
        "harness": ("StudyConfig", "StudyPlan", "StudyResult", "plan_study"),
        "report": ("level_table", "order_figure", "paper_table", "study_table", "write_study"),
        "runner": ("run_studies", "run_study"),
        "temperature": ("TableModel", "concatenate_plateaus", "global_models",
                        "held_out_comparison", "segment_noise", "segment_table",
                        "temperature_inputs", "temperature_segments", "term_standard_errors"),
    })

__all__ = [
    "StudyConfig", "StudyPlan", "StudyResult", "TableModel", "concatenate_plateaus",
    "connect_scheduler", "global_models", "held_out_comparison", "level_table", "local_client",
    "order_figure", "paper_table", "plan_study", "run_studies", "run_study", "segment_noise",
    "segment_table", "study_table", "temperature_inputs", "temperature_segments",
    "term_standard_errors", "write_study",
]
