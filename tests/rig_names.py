# SPDX-License-Identifier: GPL-3.0-or-later
"""Bone names of the rig conventions the tests rename CMU skeletons to (both suites: the
core tests rename a Skeleton, the Blender tests an imported armature)."""

# A CMU skeleton renamed as Mixamo and Rigify rigs name their bones (the bones those have no
# counterpart of get names of no convention).
MIXAMO = {
    "Hips": "mixamorig:Hips",
    "LowerBack": "mixamorig:Spine",
    "Spine": "mixamorig:Spine1",
    "Spine1": "mixamorig:Spine2",
    "Neck": "mixamorig:Neck",
    "Neck1": "mixamorig:NeckTwist",
    "Head": "mixamorig:Head",
    "LHipJoint": "mixamorig:LeftHipRoot",
    "RHipJoint": "mixamorig:RightHipRoot",
    "LThumb": "mixamorig:LeftHandThumb1",
    "RThumb": "mixamorig:RightHandThumb1",
    "LeftFingerBase": "mixamorig:LeftPalm",
    "RightFingerBase": "mixamorig:RightPalm",
    "LeftHandIndex1": "mixamorig:LeftHandIndex1",
    "RightHandIndex1": "mixamorig:RightHandIndex1",
}
for side in ("Left", "Right"):
    for b in ("UpLeg", "Leg", "Foot", "ToeBase", "Shoulder", "Arm", "ForeArm", "Hand"):
        MIXAMO[side + b] = f"mixamorig:{side}{b}"
RIGIFY = {
    "Hips": "DEF-spine",
    "Spine": "DEF-spine.001",
    "Spine1": "DEF-spine.003",
    "Neck": "DEF-spine.004",
    "Neck1": "DEF-spine.005",
    "Head": "DEF-spine.006",
    "LowerBack": "DEF-spine.lower",
    "LHipJoint": "DEF-pelvis.L",
    "RHipJoint": "DEF-pelvis.R",
    "LThumb": "DEF-thumb.01.L",
    "RThumb": "DEF-thumb.01.R",
    "LeftFingerBase": "DEF-palm.01.L",
    "RightFingerBase": "DEF-palm.01.R",
    "LeftHandIndex1": "DEF-f_index.01.L",
    "RightHandIndex1": "DEF-f_index.01.R",
}
for side, x in (("Left", "L"), ("Right", "R")):
    for b, r in (
        ("UpLeg", "thigh"),
        ("Leg", "shin"),
        ("Foot", "foot"),
        ("ToeBase", "toe"),
        ("Shoulder", "shoulder"),
        ("Arm", "upper_arm"),
        ("ForeArm", "forearm"),
        ("Hand", "hand"),
    ):
        RIGIFY[side + b] = f"DEF-{r}.{x}"
