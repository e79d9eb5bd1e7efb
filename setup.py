"""Copies the shipped TU-Flex case (requirements/ and data/) into the wheel.

The files live at the repository root (the SPEC's layout); a regular install
carries them as ``tuflexperf/_shipped`` so ``tuflexperf check`` works from any
directory. Editable installs read them straight from the checkout.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).parent


class BuildPyWithCase(build_py):
    def run(self) -> None:
        super().run()
        target = Path(self.build_lib) / "tuflexperf" / "_shipped"
        for folder in ("requirements", "data"):
            if (ROOT / folder).is_dir():
                shutil.copytree(ROOT / folder, target / folder, dirs_exist_ok=True)


setup(cmdclass={"build_py": BuildPyWithCase})
