import subprocess
import sys

HEAVY = ("open3d", "pybullet", "ompl", "meshcat")


def _imported_after(statement: str) -> list[str]:
    code = f"import sys; {statement}; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return [m for m in out.stdout.strip().split(",") if m]


def test_import_mavac_is_light():
    assert _imported_after("import mavac") == []


def test_subpackages_and_params_are_light():
    stmt = ("import mavac.params, mavac.paper, mavac.config, mavac.geometry, mavac.robots, mavac.vision, "
            "mavac.setups, mavac.inspection, mavac.cleaning, mavac.scrubbing, mavac.sim, mavac.planning, mavac.viz")
    assert _imported_after(stmt) == []
