"""Shared fixtures of the Python module's suite (docs/python.md).

The suite checks the bindings against the `dentsim` command on the same inputs: ctest runs it
(python/CMakeLists.txt, test `python_pytest`) with PYTHONPATH=<build>/python, DENTSIM_BINARY (the
command of the same build) and DENTSIM_SOURCE_DIR set. By hand, from the repository root:

    PYTHONPATH=build/release/python DENTSIM_BINARY=build/release/cli/dentsim \
        /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/python

The runs of the command the tests share are made once per session (short scenes: the whole suite
takes tens of seconds).
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

import dentsim

# Scene lengths [s]: long enough for the tool to be in contact (probe: from about 1.3 s; drill:
# drilling from about 1.2 s), short enough for seconds per run.
PROBE_S = 2.0
DRILL_S = 2.0


def _required_env(name):
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set (ctest sets it; see tests/python/conftest.py)")
    return value


@pytest.fixture(scope="session")
def binary():
    path = _required_env("DENTSIM_BINARY")
    assert Path(path).is_file(), path
    return path


@pytest.fixture(scope="session")
def source_dir():
    return Path(os.environ.get("DENTSIM_SOURCE_DIR", Path(__file__).resolve().parents[2]))


class Cli:
    """Runs `dentsim ARGS`: the exit status and the outputs."""

    def __init__(self, binary):
        self.binary = binary

    def __call__(self, *args, check=True):
        r = subprocess.run([self.binary, *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError(f"dentsim {' '.join(map(str, args))} exited {r.returncode}:\n"
                                 f"{r.stdout}\n{r.stderr}")
        return r

    def error(self, *args):
        """The one-line message of a command that fails with status 2 (bad input)."""
        r = self(*args, check=False)
        assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
        line = r.stderr.strip().splitlines()[-1]
        prefix = "dentsim: error: "
        assert line.startswith(prefix), line
        return line[len(prefix):]


@pytest.fixture(scope="session")
def cli(binary):
    return Cli(binary)


def read_json(path):
    with open(path) as f:
        return json.load(f)


@pytest.fixture(scope="session")
def probe_cli_run(cli, tmp_path_factory):
    """`dentsim run probe --duration PROBE_S`: its output directory."""
    out = tmp_path_factory.mktemp("probe_cli")
    cli("run", "probe", "--duration", PROBE_S, "--out", out)
    return out


@pytest.fixture(scope="session")
def drill_session(cli, tmp_path_factory):
    """`dentsim run drill --duration DRILL_S --record FILE` (fast pipeline, the default): the
    session file and the run's report."""
    d = tmp_path_factory.mktemp("drill_record")
    rec = d / "drill.rec"
    cli("run", "drill", "--duration", DRILL_S, "--record", rec, "--out", d / "out")
    return rec, read_json(d / "out" / "report.json")


@pytest.fixture(scope="session")
def excite_log(cli, tmp_path_factory):
    """A short calibration log from `dentsim excite` (the seeded series as drawn, 2 s)."""
    log = tmp_path_factory.mktemp("excite") / "log.csv"
    cli("excite", "-o", log, "--duration", 2, "--design-iterations", 0)
    return log


@pytest.fixture(scope="session")
def model():
    return dentsim.PhantomModel()
