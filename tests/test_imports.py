"""What importing a part of fosmodel pulls in: the noise analysis stays light."""

import subprocess
import sys

import pytest


@pytest.mark.parametrize("module", ["fosmodel.noise.allan", "fosmodel.noise.imu_noise"])
def test_the_allan_analysis_imports_neither_the_harness_nor_the_ar_estimators(module):
    heavy = ("fosmodel.study.harness", "fosmodel.models.baselines", "statsmodels.tsa.ar_model")
    code = f"import sys, {module}; print(sorted(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
