"""Shared by the bench plot scripts: re-run the calling script under a venv
($TESSERA_VENV, default ~/.cache/tessera-bench-venv) with the packages it needs when the
running Python lacks them."""
import importlib
import os
import subprocess
import sys

VENV = os.environ.get("TESSERA_VENV", os.path.expanduser("~/.cache/tessera-bench-venv"))


def ensure_deps(name, packages):
    try:
        for p in packages:
            importlib.import_module(p)
        return
    except ImportError:
        pass
    py = os.path.join(VENV, "bin", "python")
    if os.path.realpath(sys.executable) == os.path.realpath(py) and os.environ.get("_TESSERA_REEXEC"):
        sys.exit(f"{name}: {', '.join(packages)} still missing in {VENV}")
    if not os.path.exists(py):
        print(f"{name}: creating venv {VENV}", file=sys.stderr)
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "-q", *packages])
    os.environ["_TESSERA_REEXEC"] = "1"
    os.execv(py, [py] + sys.argv)
