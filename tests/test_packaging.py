"""Every package is a valid ROS 2 package, and its executables land where `ros2 run` looks."""
import ast
import configparser
import os
import xml.etree.ElementTree as ET

import pytest
from conftest import PACKAGES, WORKSPACE

PYTHON_PACKAGES = [p for p in PACKAGES if p != "swim_interfaces"]


def manifest(package):
    return ET.parse(WORKSPACE / "src" / package / "package.xml").getroot()


def setup_call(package):
    tree = ast.parse((WORKSPACE / "src" / package / "setup.py").read_text())
    call = next(n for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, "id", "") == "setup")
    return {k.arg: k.value for k in call.keywords}


@pytest.mark.parametrize("package", PACKAGES)
def test_manifest_names_the_package(package):
    root = manifest(package)
    assert root.get("format") == "3"
    assert root.findtext("name") == package
    assert root.findtext("license") and root.findtext("description")


@pytest.mark.parametrize("package", PYTHON_PACKAGES)
def test_python_package_layout(package):
    src = WORKSPACE / "src" / package
    assert manifest(package).findtext("export/build_type") == "ament_python"
    assert (src / "resource" / package).is_file()
    assert (src / package / "__init__.py").is_file()
    keywords = setup_call(package)
    assert ast.literal_eval(keywords["version"]) == manifest(package).findtext("version")
    config = configparser.ConfigParser()
    config.read(src / "setup.cfg")
    assert config["install"]["install_scripts"] == f"$base/lib/{package}"
    assert config["develop"]["script_dir"] == f"$base/lib/{package}"


@pytest.mark.parametrize("package", PYTHON_PACKAGES)
def test_console_scripts_are_installed_for_ros2_run(package):
    keywords = setup_call(package)
    scripts = ast.literal_eval(keywords["entry_points"]).get("console_scripts", [])
    for entry in scripts:
        name = entry.split("=")[0].strip()
        executable = WORKSPACE / "install" / package / "lib" / package / name
        assert executable.is_file() and os.access(executable, os.X_OK), executable


def test_interface_package_is_a_rosidl_package():
    root = manifest("swim_interfaces")
    assert root.findtext("export/build_type") == "ament_cmake"
    assert root.findtext("member_of_group") == "rosidl_interface_packages"
    cmake = (WORKSPACE / "src" / "swim_interfaces" / "CMakeLists.txt").read_text()
    for folder in ("msg", "srv", "action"):
        for path in (WORKSPACE / "src" / "swim_interfaces" / folder).iterdir():
            assert f'"{folder}/{path.name}"' in cmake, f"{path.name} is not generated"


@pytest.mark.parametrize("package", PYTHON_PACKAGES)
def test_installed_package_is_marked_typed(package):
    """PEP 561: the py.typed marker installs with the package, so a type checker outside the workspace reads its
    annotations."""
    import importlib
    installed = importlib.import_module(package).__path__[0]
    assert os.path.isfile(os.path.join(installed, "py.typed")), f"{package} installs no py.typed in {installed}"
