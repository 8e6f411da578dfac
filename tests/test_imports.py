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


#: What a command's start must not load: the libraries of the commands themselves.
COMMANDS_LIBRARIES = ("sklearn", "statsmodels", "matplotlib", "scipy", "pandas", "allantools",
                      "dask", "data_synth.scenarios", "fosmodel.models.model",
                      "fosmodel.cli.commands")


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["study", "--help"],
                                  ["imu", "--help"], ["synth", "--help"]])
def test_the_command_line_starts_without_the_libraries_of_the_commands(argv):
    """``fosmodel --version`` and every ``--help`` build the parser of every command and stop:
    none of the commands' libraries may load (the start-up benchmark times what is left)."""
    code = ("import runpy, sys\n"
            f"sys.argv = ['fosmodel', *{argv!r}]\n"
            "try:\n    runpy.run_module('fosmodel.cli', run_name='__main__')\n"
            "except SystemExit:\n    pass\n"
            f"print(sorted(m for m in {COMMANDS_LIBRARIES!r} if m in sys.modules), "
            "file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stderr.strip().splitlines()[-1] == "[]"


def test_the_package_s_names_are_imported_when_first_used():
    code = ("import sys, fosmodel; assert 'sklearn' not in sys.modules; "
            "from fosmodel import FOSModel, NotFittedError, InputError; "
            "from sklearn.exceptions import NotFittedError as Sk; "
            "assert issubclass(NotFittedError, Sk) and issubclass(NotFittedError, InputError); "
            "assert FOSModel.__module__ == 'fosmodel.models.model'; "
            "import pickle; e = pickle.loads(pickle.dumps(NotFittedError('x'))); "
            "assert type(e) is NotFittedError; print(dir(fosmodel) == sorted(fosmodel.__all__))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True"


def test_the_names_the_parser_spells_are_the_library_s():
    """The parser spells the stopping rules and the methods, not to import their modules."""
    from fosmodel.cli.imu import METHODS
    from fosmodel.cli.parser import STOP_RULES
    from fosmodel.core.fos import STOP_RULES as RULES
    from fosmodel.study.harness import METHODS as STUDIED

    assert STOP_RULES == RULES and METHODS == STUDIED
