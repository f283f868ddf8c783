"""A pose as the curves a rig keys (kinematics/pose_keys.py), without Blender."""

from motion_patches.kinematics import pose_keys


def test_rest_values_are_blenders_defaults_of_each_channel():
    """What a channel plays where no strip keys it: a quaternion (1, 0, 0, 0), an axis-angle
    (0, 0, 1, 0), an Euler angle and a location 0."""
    curves = (
        [('pose.bones["A"].rotation_quaternion', i, "A", None) for i in range(4)]
        + [('pose.bones["B"].rotation_axis_angle', i, "B", None) for i in range(4)]
        + [('pose.bones["C"].rotation_euler', i, "C", None) for i in range(3)]
        + [('pose.bones["C"].location', i, "C", None) for i in range(3)]
    )
    got = pose_keys.rest_values(curves)
    assert got.tolist() == [1, 0, 0, 0, 0, 0, 1, 0] + [0] * 6
