import sys
import types

import pytest

from swim_ros.exports import lazy_exports


def test_a_name_is_imported_from_its_module_on_first_use():
    __all__, getattr_ = lazy_exports("swim_ros", {"domains": ("claim_ros_domain",), "codecs": ("stamp_of",)})
    assert __all__ == ["claim_ros_domain", "stamp_of"]
    sys.modules.pop("swim_ros.domains", None)
    function = getattr_("claim_ros_domain")
    assert "swim_ros.domains" in sys.modules
    assert function is sys.modules["swim_ros.domains"].claim_ros_domain


def test_an_unknown_name_is_an_attribute_error():
    _, getattr_ = lazy_exports("swim_ros", {"domains": ("claim_ros_domain",)})
    with pytest.raises(AttributeError, match="has no attribute 'run_domain'"):
        getattr_("run_domain")


def test_a_package_exports_only_what_its_modules_define():
    import swim_ros
    assert isinstance(swim_ros, types.ModuleType)
    for name in swim_ros.__all__:
        assert getattr(swim_ros, name) is not None
    with pytest.raises(AttributeError):
        swim_ros.not_a_name  # noqa: B018
