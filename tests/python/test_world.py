"""fluiddemo.World: scenes, steps, and positions/velocities as views of the world's own memory."""
import numpy as np
import pytest

import fluiddemo


def small_dambreak():
    return fluiddemo.World("dambreak", width="0.1", spacing="0.01")


def test_positions_and_velocities_are_views_of_the_world():
    world = small_dambreak()
    positions, velocities = world.positions, world.velocities
    assert positions.base is world and velocities.base is world
    assert positions.shape == (len(world), 3) and positions.dtype == np.float32
    assert not positions.flags.owndata and not positions.flags.writeable
    # The same memory on every access (no copy made per access).
    assert np.shares_memory(world.positions, positions)
    assert world.positions.__array_interface__["data"][0] == positions.__array_interface__["data"][0]


def test_steps_move_the_water_down():
    world = small_dambreak()
    top = world.positions[:, 1].max()
    world.advance(0.1)
    assert world.time == pytest.approx(0.1)
    assert world.positions[:, 1].max() < top
    assert (world.velocities[:, 1] < 0).mean() > 0.5
    assert world.step() > 0.0


def test_the_view_keeps_the_world_alive():
    positions = small_dambreak().positions
    assert positions.base is not None and np.isfinite(positions).all()


def test_scene_errors_carry_the_library_messages():
    with pytest.raises(ValueError, match="unknown scene 'nope'"):
        fluiddemo.World("nope")
    with pytest.raises(ValueError, match="width"):
        fluiddemo.World("dambreak", width="-1")
    with pytest.raises(ValueError, match="unknown solver"):
        fluiddemo.World("dambreak", solver="euler")
    assert "dambreak" in fluiddemo.scene_names()
