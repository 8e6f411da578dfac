"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors.

The package's face: the names most work starts from, each also public in its layer's
subpackage (``fosmodel.io.load_record`` is ``fosmodel.load_record``).  They are imported on
first use (:mod:`fosmodel._lazy`, PEP 562), so that ``import fosmodel`` and the command
line's start (``fosmodel --version``, ``--help``) pay for scikit-learn, SciPy and pandas only
when a command or a user reaches for what needs them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._lazy import attach
from ._version import __version__

if TYPE_CHECKING:
    from .core.candidates import CandidateSpec, Term, count_candidates, generate_terms
    from .core.exceptions import FOSModelError, InputError, NotFittedError, UnstableModelWarning
    from .core.fos import FOSResult, StopRule, fos
    from .filter.joint_noise import joint_noise
    from .filter.statespace import to_state_space
    from .io.loader import load_record
    from .loop.closeloop import LoopConfig, close_loop
    from .models.baselines import ARModel, GaussMarkovModel
    from .models.model import FOSModel
    from .models.narx_features import NARXFeatures, lagged_rows
    from .models.regressor import FOSRegressor
    from .noise.allan import AllanResult, allan_deviation
    from .noise.allan_fit import NoiseFit, fit_noise
    from .noise.imu_noise import imu_noise
    from .study.harness import StudyConfig
    from .study.runner import run_study
    from .workflows.fleet import run_fleet
    from .workflows.imu import ImuConfig, run_imu
else:
    __getattr__, __dir__ = attach(__name__, {
        "core.candidates": ("CandidateSpec", "Term", "count_candidates", "generate_terms"),
        "core.exceptions": ("FOSModelError", "InputError", "NotFittedError",
                            "UnstableModelWarning"),
        "core.fos": ("FOSResult", "StopRule", "fos"),
        "filter.statespace": ("to_state_space",),
        "io.loader": ("load_record",),
        "loop.closeloop": ("LoopConfig", "close_loop"),
        "models.baselines": ("ARModel", "GaussMarkovModel"),
        "models.model": ("FOSModel",),
        "models.narx_features": ("NARXFeatures", "lagged_rows"),
        "models.regressor": ("FOSRegressor",),
        "noise.allan": ("AllanResult", "allan_deviation"),
        "noise.allan_fit": ("NoiseFit", "fit_noise"),
        "filter.joint_noise": ("joint_noise",),
        "noise.imu_noise": ("imu_noise",),
        "study.harness": ("StudyConfig",),
        "study.runner": ("run_study",),
        "workflows.fleet": ("run_fleet",),
        "workflows.imu": ("ImuConfig", "run_imu"),
    })

__all__ = [
    "ARModel", "AllanResult", "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor",
    "FOSResult", "GaussMarkovModel", "ImuConfig", "InputError", "LoopConfig", "NARXFeatures",
    "NoiseFit", "NotFittedError", "StopRule", "StudyConfig", "Term", "UnstableModelWarning",
    "__version__", "allan_deviation", "close_loop", "count_candidates", "fit_noise", "fos",
    "generate_terms", "imu_noise", "joint_noise", "lagged_rows", "load_record", "run_fleet",
    "run_imu", "run_study", "to_state_space",
]
