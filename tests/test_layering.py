"""The engine stands alone: importing every ``rcengine`` module loads neither the service nor its
web and database stack (the engine is the lower layer; the service is one shell over it)."""

import json
import subprocess
import sys

FORBIDDEN = ("service", "fastapi", "sqlalchemy")

IMPORT_ALL = """
import importlib, json, pkgutil, sys
import rcengine
names = [m.name for m in pkgutil.walk_packages(rcengine.__path__, "rcengine.")]
for name in names:
    importlib.import_module(name)
loaded = sorted({m.split(".")[0] for m in sys.modules} & set(sys.argv[1:]))
print(json.dumps({"modules": names, "loaded": loaded}))
"""


def test_no_rcengine_module_imports_the_service_stack():
    run = subprocess.run(
        [sys.executable, "-c", IMPORT_ALL, *FORBIDDEN],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout.strip().splitlines()[-1])
    # The walk saw the whole package, sub-packages included.
    assert {"rcengine.cli", "rcengine.diagnose.candidates", "rcengine.signals.derived"} <= set(
        result["modules"]
    )
    assert result["loaded"] == [], f"rcengine imports {result['loaded']}"
