import subprocess
import sys

FORBIDDEN = ("torch", "lerobot", "gymnasium", "rerun", "huggingface_hub", "pymunk", "cv2")


def test_the_core_imports_no_heavy_library():
    code = (
        "import pkgutil, importlib, sys, lerobot_contrast.contrast as c\n"
        "for m in pkgutil.iter_modules(c.__path__): importlib.import_module('lerobot_contrast.contrast.' + m.name)\n"
        f"print(sorted(n for n in sys.modules if n.split('.')[0] in {FORBIDDEN!r}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
