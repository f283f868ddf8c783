# SPDX-License-Identifier: GPL-3.0-or-later
"""The planning settings' defaults, in one place: the Eq. 5 cost weights, the character's
radius, the stitching mode, foot locking and goal facing. The scene's Planning settings and
the add-on preferences start from them (``props.PLANNING``), the API fills every setting a
caller leaves out from the scene's, and the core planner and the benches use them too."""

PLANNING = {
    "alpha": 1.0,  # cost per metre walked
    "beta": 0.5,  # cost per radian turned
    "gamma": 0.2,  # cost per unit of effort
    "radius": 0.25,  # metres kept between the root and props
    "stitching": "dynamic",  # "dynamic" (lazy, the paper's method) or "static" (Lee 2006)
    "foot_lock": True,  # pin planted feet with leg IK
    "goal_facing": "exact",  # "exact": arrive facing the goal's heading; "any": the cheapest
    "turn_in_place": True,  # turn on the spot where a walk would loop (a derived turn)
}
STITCHING = ("dynamic", "static")
GOAL_FACING = ("exact", "any")
