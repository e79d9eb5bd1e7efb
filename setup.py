"""Copies the shipped TU-Flex case (requirements/ and data/) into the wheel.

The files live at the repository root (the SPEC's layout); a regular install
carries them as ``tuflexperf/_shipped`` so ``tuflexperf check`` works from any
directory. Editable installs read them straight from the checkout, and compile
the package's bytecode in it, as pip does for a regular install.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.editable_wheel import editable_wheel

ROOT = Path(__file__).parent


class BuildPyWithCase(build_py):
    def run(self) -> None:
        super().run()
        target = Path(self.build_lib) / "tuflexperf" / "_shipped"
        for folder in ("requirements", "data"):
            if (ROOT / folder).is_dir():
                shutil.copytree(ROOT / folder, target / folder, dirs_exist_ok=True)


class EditableWithBytecode(editable_wheel):
    """An editable install that also compiles the checkout's bytecode, once.

    pip compiles a regular install's modules when it installs them; an editable one is
    compiled by the first import, unless PYTHONDONTWRITEBYTECODE is set (containers, CI):
    then every ``tuflexperf`` start compiled every module again (~80 ms of each ``check``).
    A failure here costs only that time, never the install.
    """

    def run(self) -> None:
        super().run()
        import compileall

        try:
            compileall.compile_dir(str(ROOT / "tuflexperf"), quiet=1)
        except Exception as exc:  # noqa: BLE001 - speed only: the install must go on
            print(f"tuflexperf: bytecode not compiled ({exc})")


setup(cmdclass={"build_py": BuildPyWithCase, "editable_wheel": EditableWithBytecode})
