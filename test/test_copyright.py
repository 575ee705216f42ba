# ament standard linter tests (run under colcon test with ROS 2; skipped without ament).
import pytest


@pytest.mark.skip(reason='No copyright header has been placed in the generated source file.')
@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    main = pytest.importorskip('ament_copyright.main').main
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'
