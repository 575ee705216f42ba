# ament standard linter tests (run under colcon test with ROS 2; skipped without ament).
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    main = pytest.importorskip('ament_pep257.main').main
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'
