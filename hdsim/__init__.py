"""hdsim: a harmonic drive (strain wave gear) simulator.

The names below are the public interface; everything else lives in the layered
subpackages (docs/architecture.md).

```python
import hdsim

drive = hdsim.load_unit("CSG-25-100").with_updates({"flexspline.h_c": 0.8e-3})
run = hdsim.run_scenario(drive, "lost_motion")
print(run.metric("lost_motion_arcmin"))
```

| name | what it is |
|---|---|
| `load_unit` | a built-in unit, or any drive from its drive file (TOML), as a `HarmonicDrive` |
| `HarmonicDrive` | the model: geometry, calibration, inertias and effect slots |
| `run_scenario` | simulate a scenario (built-in name, file or `Scenario`) on a drive |
| `load_scenario`, `Scenario` | a validated scenario |
| `Run`, `read_run` | a finished run (`.metric`, `.save`) and reading one back |
| `sobol` | Sobol' indices of a metric with respect to parameters of any drive |
| `load_measurement` | a bench measurement file (CSV or HDF5) |
| `measurement_from_run` | a run of hdsim's own as a bench record (closing the loop simulate → fit) |
| `fit`, `diagnose` | fit a model to a measurement; find the effects it lacks, with the data checks, the outcome, the next measurement and the report |

`import hdsim` stays light: each name is imported from its module the first time it
is used, so the solvers, HDF5 and plotting load only when needed.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from hdsim._version import __version__

#: public name -> module defining it (imported on first access)
_EXPORTS = {
    "load_unit": "hdsim.model.catalog",
    "HarmonicDrive": "hdsim.model.drive",
    "run_scenario": "hdsim.scenarios.run",
    "load_scenario": "hdsim.scenarios.scenario",
    "Scenario": "hdsim.scenarios.scenario",
    "Run": "hdsim.scenarios.run",
    "read_run": "hdsim.scenarios.run",
    "sobol": "hdsim.sensitivity.api",
    "load_measurement": "hdsim.io.measurement",
    "measurement_from_run": "hdsim.io.measurement",
    "fit": "hdsim.identification.workflow",
    "diagnose": "hdsim.identification.workflow",
}

__all__ = ["__version__", *_EXPORTS]

if TYPE_CHECKING:  # type checkers and IDEs see the real signatures
    from hdsim.identification.workflow import diagnose, fit
    from hdsim.io.measurement import load_measurement, measurement_from_run
    from hdsim.model.catalog import load_unit
    from hdsim.model.drive import HarmonicDrive
    from hdsim.scenarios.run import Run, read_run, run_scenario
    from hdsim.scenarios.scenario import Scenario, load_scenario
    from hdsim.sensitivity.api import sobol


def __getattr__(name: str):
    # PEP 562: eager imports would cost about a second (scipy, h5py) on every start
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'hdsim' has no attribute '{name}'")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
