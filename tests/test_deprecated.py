import importlib
import sys

import pytest

OLD_TO_NEW = {
    "mavac.mobile.plan": "mavac.inspection.plan",
    "mavac.mobile.greedy": "mavac.planning.greedy",
    "mavac.setups.setcover": "mavac.planning.setcover",
    "mavac.setups.toolpath": "mavac.scrubbing.toolpath",
    "mavac.sim.scrub": "mavac.sim.wear",
}


@pytest.mark.parametrize("old, new", OLD_TO_NEW.items())
def test_old_path_warns_and_is_the_new_module(old, new):
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=new):
        mod = importlib.import_module(old)
    assert mod is importlib.import_module(new)


def test_from_old_path_import_name():
    sys.modules.pop("mavac.mobile.plan", None)
    with pytest.warns(DeprecationWarning):
        from mavac.mobile.plan import plan_inspection
    from mavac.inspection.plan import plan_inspection as new
    assert plan_inspection is new
