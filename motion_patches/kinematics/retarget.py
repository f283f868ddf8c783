# SPDX-License-Identifier: GPL-3.0-or-later
"""Bone maps and retargeting: the one place where motion of one skeleton is put on another.

A locomotion patch, a clip or a planned motion carries its skeleton (bone names, parents,
armature-space rest matrices: :class:`~motion_patches.kinematics.skeleton.Skeleton`). A character
may
be another rig: the same bone names with other lengths (another CMU subject), or another
naming convention altogether. :func:`rig_map` pairs the bones of the two skeletons and
:class:`RigMap` moves motion across; clips (mocap import, object-patch clips), patch
segments and whole plans all go through it.

**Pairing.** Each skeleton's bones are given *roles* (hips, thigh, shin, foot, toe, spine,
neck, head, collar, upper arm, ...) by the naming convention that recognises most of them:
CMU / MotionBuilder (``Hips``, ``LeftUpLeg``, ``LeftLeg``, ``LeftFoot``, ``LeftToeBase``,
``LowerBack``, ``Spine``...), the 3ds Max Biped-like CMU conversion (``LeftHip``,
``LeftKnee``, ``LeftAnkle``, ``LeftToe``, ``lowerback``, ``Chest``, ``Chest2``...),
Mixamo (``mixamorig:Hips``, ``mixamorig:LeftUpLeg``...) and Rigify deform bones
(``DEF-spine``, ``DEF-thigh.L``, ``DEF-shin.L``...). A ``namespace:`` prefix and the case
are ignored. Bones pair by role; bones left without a role pair by equal name when both
skeletons follow the same convention (two CMU subjects pair every bone). A user map
``{patch bone: rig bone}`` (``""``: leave that patch bone out) overrides the guess. The
hips, thighs, shins, feet and toes must pair; otherwise :class:`RetargetError` names the
patch bones that could not be mapped.

**Rule.** Each bone keeps its armature-space rotation *relative to its rest pose*: with
``D = G_src @ inv(rest_src)`` the bone's turn away from its rest orientation, the paired
target bone gets ``G_tgt = D @ A @ Y @ rest_tgt``. ``Y`` turns the target about Z so its
rest facing is the source's, and ``A`` is the shortest turn that points the target bone,
in its rest pose, where the source bone points in its own (bone directions are taken from
head to the head of the next paired bone down the chain, so they do not depend on bone
rolls). When both rest poses agree (the same stance, as two BVH subjects), ``A`` is almost
the identity and this is the plain rest-relative rule; when they do not (a rig resting
with its arms down, an A-pose) the aligned rest keeps the limbs where the source puts
them. Unpaired target bones keep their rest pose relative to their parent.
Root motion is scaled by the ratio of hip heights (hips above the lowest foot or toe joint
in the rest pose), about a floor height: the character takes the same number of steps,
each in proportion to its legs.

The target is the rig's bones below the bone paired with the source root (a rig whose
hips hang under a ground "root" bone is driven from the hips down; the bones above stay
in their rest pose).
"""

import hashlib
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import quat
from .clip import Clip
from .motion import Motion
from .skeleton import Skeleton, forward_kinematics, local_rotations_from_global


class RetargetError(ValueError):
    """The skeletons cannot be paired; the message names the patch bones left unmapped."""


SIDES = ("Left", "Right")
# Roles every character must have for a walk to be planned on it (root motion, contacts,
# foot locking, facing).
REQUIRED = ("hips", "thigh.L", "shin.L", "foot.L", "toe.L", "thigh.R", "shin.R", "foot.R", "toe.R")


def _sided(table):
    """Expand '{S}' / '{s}' / '{x}' placeholders to both sides: role '.L' and '.R'."""
    out = {}
    for role, names in table.items():
        if "{" not in role:
            out[role] = names
            continue
        for side, s, x in (("Left", "l", "L"), ("Right", "r", "R")):
            out[role.format(x=x)] = tuple(n.format(S=side, s=s, x=x, X=s.upper()) for n in names)
    return out


CONVENTIONS = {
    # CMU BVH, MotionBuilder-friendly joint names (shared/mocap/cmu).
    "CMU": _sided(
        {
            "hips": ("Hips",),
            "lowerback": ("LowerBack",),
            "spine": ("Spine",),
            "chest": ("Spine1",),
            "neck": ("Neck",),
            "neck1": ("Neck1",),
            "head": ("Head",),
            "hipjoint.{x}": ("{X}HipJoint",),
            "thigh.{x}": ("{S}UpLeg",),
            "shin.{x}": ("{S}Leg",),
            "foot.{x}": ("{S}Foot",),
            "toe.{x}": ("{S}ToeBase",),
            "collar.{x}": ("{S}Shoulder",),
            "upper_arm.{x}": ("{S}Arm",),
            "forearm.{x}": ("{S}ForeArm",),
            "hand.{x}": ("{S}Hand",),
            "fingers.{x}": ("{S}FingerBase",),
            "index.{x}": ("{S}HandIndex1",),
            "thumb.{x}": ("{X}Thumb",),
        }
    ),
    # CMU's "3dsMax-friendly" BVH conversion, Biped-like names (shared/mocap/cmu16max).
    "3ds Max": _sided(
        {
            "hips": ("Hips",),
            "lowerback": ("lowerback",),
            "spine": ("Chest",),
            "chest": ("Chest2",),
            "neck": ("lowerneck",),
            "neck1": ("Neck",),
            "head": ("Head",),
            "hipjoint.{x}": ("{X}HipJoint",),
            "thigh.{x}": ("{S}Hip",),
            "shin.{x}": ("{S}Knee",),
            "foot.{x}": ("{S}Ankle",),
            "toe.{x}": ("{S}Toe",),
            "collar.{x}": ("{S}Collar",),
            "upper_arm.{x}": ("{S}Shoulder",),
            "forearm.{x}": ("{S}Elbow",),
            "hand.{x}": ("{S}Wrist",),
            "fingers.{x}": ("{s}hand",),
            "index.{x}": ("{X}Fingers",),
            "thumb.{x}": ("{X}Thumb",),
        }
    ),
    # Mixamo (the "mixamorig:" namespace is ignored when matching).
    "Mixamo": _sided(
        {
            "hips": ("Hips",),
            "lowerback": ("Spine",),
            "spine": ("Spine1",),
            "chest": ("Spine2",),
            "neck": ("Neck",),
            "head": ("Head",),
            "thigh.{x}": ("{S}UpLeg",),
            "shin.{x}": ("{S}Leg",),
            "foot.{x}": ("{S}Foot",),
            "toe.{x}": ("{S}ToeBase",),
            "collar.{x}": ("{S}Shoulder",),
            "upper_arm.{x}": ("{S}Arm",),
            "forearm.{x}": ("{S}ForeArm",),
            "hand.{x}": ("{S}Hand",),
            "index.{x}": ("{S}HandIndex1",),
            "thumb.{x}": ("{S}HandThumb1",),
        }
    ),
    # Rigify deform bones. DEF-spine runs from the hips up (there is no separate hips bone).
    "Rigify": _sided(
        {
            "hips": ("DEF-spine",),
            "spine": ("DEF-spine.001",),
            "chest": ("DEF-spine.003",),
            "neck": ("DEF-spine.004",),
            "neck1": ("DEF-spine.005",),
            "head": ("DEF-spine.006",),
            "thigh.{x}": ("DEF-thigh.{x}",),
            "shin.{x}": ("DEF-shin.{x}",),
            "foot.{x}": ("DEF-foot.{x}",),
            "toe.{x}": ("DEF-toe.{x}",),
            "collar.{x}": ("DEF-shoulder.{x}",),
            "upper_arm.{x}": ("DEF-upper_arm.{x}",),
            "forearm.{x}": ("DEF-forearm.{x}",),
            "hand.{x}": ("DEF-hand.{x}",),
            "thumb.{x}": ("DEF-thumb.01.{x}",),
            "index.{x}": ("DEF-f_index.01.{x}",),
        }
    ),
}


def base_name(name: str) -> str:
    """A bone name without a ``namespace:`` prefix, lower case (how names are compared)."""
    return name.rsplit(":", 1)[-1].lower()


def _exclusive():
    """Per convention, the (lower-case) names no other convention uses."""
    used = {c: {n.lower() for names in t.values() for n in names} for c, t in CONVENTIONS.items()}
    return {
        c: names - set().union(*(u for d, u in used.items() if d != c)) for c, names in used.items()
    }


def roles(skel: Skeleton) -> tuple[str, dict[str, int]]:
    """(convention, {role: bone index}) of the convention that names the skeleton's bones
    best: one point per role it finds, one more when the name found is the convention's
    own (CMU's ``Neck1``, Mixamo's ``Spine2``: the conventions share most names); ties go
    to the first in :data:`CONVENTIONS`."""
    lower: dict[str, int] = {}
    for i, n in enumerate(skel.names):
        lower.setdefault(base_name(n), i)
    own = _exclusive()
    best: tuple[str, dict[str, int]] = ("", {})
    best_score = 0
    for conv, table in CONVENTIONS.items():
        found, score = {}, 0
        for role, names in table.items():
            for n in names:
                if n.lower() in lower:
                    found[role] = lower[n.lower()]
                    score += 1 + (n.lower() in own[conv])
                    break
        if score > best_score:
            best, best_score = (conv, found), score
    return best


def hip_height(skel: Skeleton, hips: int, feet: Sequence[int]) -> float:
    """Standing height of the hips joint above the lowest of the ``feet`` joints (rest)."""
    z = skel.rest[:, 2, 3]
    return float(z[hips] - min(z[f] for f in feet))


def _rotation_between(u, v):
    """3x3 rotation taking unit vector u to v along the shortest arc."""
    axis = np.cross(u, v)
    s, c = np.linalg.norm(axis), float(np.clip(np.dot(u, v), -1.0, 1.0))
    if s < 1e-9:
        if c > 0:
            return np.eye(3)
        perp = np.cross(u, [1.0, 0.0, 0.0])
        if np.linalg.norm(perp) < 1e-6:
            perp = np.cross(u, [0.0, 1.0, 0.0])
        axis, s = perp / np.linalg.norm(perp), 0.0
        return quat.to_matrix(quat.exp(axis * np.pi))
    return quat.to_matrix(quat.exp(axis / s * np.arctan2(s, c)))


def _descendants(skel):
    """Set of descendant indices of every bone."""
    children = [[] for _ in skel.names]
    for j, p in enumerate(skel.parents):
        if p >= 0:
            children[p].append(j)
    out = [set() for _ in skel.names]
    for j in reversed(range(len(skel.names))):  # parents come before children
        for c in children[j]:
            out[j] |= {c} | out[c]
    return out


def subtree(skel: Skeleton, root: int) -> Skeleton:
    """The skeleton of bone ``root`` and everything below it (parents remapped)."""
    keep = [root] + sorted(_descendants(skel)[root])
    keep.sort()
    index = {j: i for i, j in enumerate(keep)}
    parents = np.array([index.get(int(skel.parents[j]), -1) if j != root else -1 for j in keep])
    return Skeleton([skel.names[j] for j in keep], parents, skel.rest[keep].copy())


@dataclass
class RigMap:
    """How motion on ``source`` is put on ``target`` (see the module docstring)."""

    source: Skeleton
    target: Skeleton
    pairs: np.ndarray  # (K, 2) source index, target index
    scale: float  # root motion scale: target hip height / source hip height
    floor: float  # height about which root heights are scaled
    yaw: np.ndarray  # (3, 3) turn of the target's rest facing onto the source's
    align: np.ndarray  # (K, 3, 3) shortest turn of each target bone's rest direction
    convention: tuple = ("", "")  # (source, target) naming conventions recognised
    unmapped: list = field(default_factory=list)  # source bones no target bone plays

    @property
    def mapping(self) -> dict[str, str]:
        """{source bone name: target bone name}."""
        return {self.source.names[s]: self.target.names[t] for s, t in self.pairs}

    def signature(self) -> str:
        """Short hash of everything that shapes the retargeted motion: rigs with the same
        skeleton and map share it (and so share retargeted segment actions)."""
        h = hashlib.sha1()
        for skel in (self.source, self.target):
            h.update("\x00".join(skel.names).encode())
            h.update(np.round(skel.rest, 5).tobytes())
        h.update(self.pairs.astype(np.int64).tobytes())
        h.update(np.round([self.scale, self.floor], 6).tobytes())
        return h.hexdigest()[:10]

    def note(self) -> str:
        """One line for reports: conventions, scale and what is left out."""
        src, tgt = self.convention
        text = (
            f"retargeted from {src or 'the patch'} naming onto {tgt or 'the rig'} naming, "
            f"{len(self.pairs)} bones, root motion x{self.scale:.3f}"
        )
        if self.unmapped:
            text += f"; patch bones not played: {', '.join(self.unmapped[:8])}"
            if len(self.unmapped) > 8:
                text += f" and {len(self.unmapped) - 8} more"
        return text

    def global_rotations(self, src_global: np.ndarray) -> np.ndarray:
        """Target armature-space rotations (F, Jt, 3, 3) from source ones (F, Js, 3, 3)."""
        src, tgt = self.source, self.target
        nf = src_global.shape[0]
        s_idx, t_idx = self.pairs[:, 0], self.pairs[:, 1]
        delta = src_global[:, s_idx] @ np.swapaxes(src.rest[s_idx, :3, :3], -1, -2)[None]
        aligned_rest = self.align @ self.yaw[None] @ tgt.rest[t_idx, :3, :3]
        out = np.empty((nf, len(tgt.names), 3, 3))
        out[:, t_idx] = delta @ aligned_rest[None]
        mapped = np.zeros(len(tgt.names), bool)
        mapped[t_idx] = True
        local_rest = tgt.local_rest()
        root_rest = self.yaw @ tgt.rest[tgt.root, :3, :3]
        for j, p in enumerate(tgt.parents):
            if mapped[j]:
                continue
            if p < 0:  # an unpaired root (never, as the root is paired): rest, turned by Y
                out[:, j] = root_rest
            else:
                out[:, j] = out[:, p] @ local_rest[j, :3, :3]
        return out

    def rotations(self, src_rotations: np.ndarray) -> np.ndarray:
        """Target pose rotation channels (F, Jt, 4) from source ones (F, Js, 4)."""
        g = forward_kinematics(self.source, np.zeros((len(src_rotations), 3)), src_rotations)
        return local_rotations_from_global(self.target, self.global_rotations(g[..., :3, :3]))

    def position(self, root_pos: np.ndarray) -> np.ndarray:
        """Target root head positions (F, 3) from the source's: scaled about the floor."""
        p = np.array(root_pos, float) * self.scale
        p[:, 2] = self.floor + (np.asarray(root_pos)[:, 2] - self.floor) * self.scale
        return p

    def clip(self, clip: Clip, name: str | None = None) -> Clip:
        """The clip on the target skeleton."""
        tags = dict(clip.tags)
        tags["retargeted_from"] = clip.name
        return Clip(
            name or clip.name,
            self.target,
            clip.fps,
            self.position(clip.root_pos),
            self.rotations(clip.rotations),
            tags,
        )

    def motion(self, m: Motion) -> Motion:
        """A planned (in-place) motion on the target: ground positions and the root's
        offset from the ground frame scaled, rotations retargeted, contacts kept."""
        g = m.ground.copy()
        g[:, :2] *= self.scale
        return Motion(g, self.position(m.root_local), self.rotations(m.rotations), m.contacts)


def _lateral(skel, left, right):
    a = skel.rest[left, :3, 3] - skel.rest[right, :3, 3]
    a[2] = 0.0
    n = np.linalg.norm(a)
    if n < 1e-9:
        raise RetargetError(
            "the rig's thighs sit on top of each other: cannot tell which way it faces"
        )
    return a / n


def _aims(source, target, pairs, lat_s, eps=1e-4):
    """For each pair (source bone, target bone), the pair to aim at: the nearest paired
    bones below both whose heads are away from theirs; of several, the one nearest the
    body's midline (the spine over the thighs, the neck over the collars), then the
    farthest. None where there is none."""
    desc_s, desc_t = _descendants(source), _descendants(target)
    hs, ht = source.rest[:, :3, 3], target.rest[:, :3, 3]
    out = []
    for si, ti in pairs:
        cands = [
            (a, b)
            for a, b in pairs
            if a in desc_s[si]
            and b in desc_t[ti]
            and np.linalg.norm(hs[a] - hs[si]) > eps
            and np.linalg.norm(ht[b] - ht[ti]) > eps
        ]
        cands = [c for c in cands if not any(c[0] in desc_s[d[0]] for d in cands if d != c)]
        if not cands:
            out.append(None)
            continue
        cands.sort(
            key=lambda c: (
                round(abs(float(np.dot(hs[c[0]] - hs[si], lat_s))), 2),
                -float(np.linalg.norm(hs[c[0]] - hs[si])),
            )
        )
        out.append(cands[0])
    return out


def rig_map(
    source: Skeleton,
    target: Skeleton,
    overrides: dict[str, str] | None = None,
    floor: float = 0.0,
    label: str = "patch",
) -> "RigMap":
    """The :class:`RigMap` from skeleton ``source`` (a patch's, a clip's) onto ``target``
    (a rig's), pairing bones by role and ``overrides`` ({source bone: target bone or ""}).

    Raises :class:`RetargetError` naming the source bones of the hips, legs, feet and toes
    that no target bone plays (``label`` names the source in messages: "patch", "clip")."""
    overrides = dict(overrides or {})
    for s, t in overrides.items():
        if s not in source.names:
            raise RetargetError(
                f"the bone map names '{s}', which is not a bone of the {label} skeleton"
            )
        if t and t not in target.names:
            raise RetargetError(f"the bone map maps '{s}' to '{t}', which is not a bone of the rig")
    s_conv, s_roles = roles(source)
    t_conv, t_roles = roles(target)
    pairs = {}
    if source.names == target.names or set(source.names) == set(target.names):
        pairs = {s: target.names.index(s) for s in source.names}
        pairs = {source.names.index(s): t for s, t in pairs.items()}
    else:
        for role, si in s_roles.items():
            if role in t_roles:
                pairs[si] = t_roles[role]
        if s_conv == t_conv:  # bones without a role pair by equal name
            used_s = set(s_roles.values())
            used_t = set(t_roles.values())
            lower_t = {n.lower(): i for i, n in enumerate(target.names)}
            for si, n in enumerate(source.names):
                ti = lower_t.get(n.lower())
                if si not in used_s and ti is not None and ti not in used_t:
                    pairs[si] = ti
    for s, t in overrides.items():
        si = source.names.index(s)
        if t:
            pairs = {a: b for a, b in pairs.items() if b != target.names.index(t)}
            pairs[si] = target.names.index(t)
        else:
            pairs.pop(si, None)
    required = []
    for role in REQUIRED:
        found = s_roles.get(role)
        if found is None:
            raise RetargetError(
                f"the {label} skeleton has no bone for the {role} (none of "
                f"the naming conventions {', '.join(CONVENTIONS)} names it)"
            )
        required.append(found)
    missing = [source.names[si] for si in required if si not in pairs]
    if missing:
        raise RetargetError(
            f"no bone of the rig plays the {label} bones {', '.join(missing)}: name the rig's "
            f"bones in a supported convention ({', '.join(CONVENTIONS)}) or map them in its "
            f"bone map"
        )
    root_s = source.root
    if root_s not in pairs:
        raise RetargetError(
            f"no bone of the rig plays the {label}'s root bone '{source.names[root_s]}'"
        )
    # The target: the rig below the bone playing the source root.
    full = target
    tree = subtree(full, pairs[root_s])
    new_index = {n: i for i, n in enumerate(tree.names)}
    outside = [source.names[si] for si, ti in pairs.items() if full.names[ti] not in new_index]
    if outside:
        raise RetargetError(
            f"the rig's bones playing {', '.join(outside[:6])} are not below "
            f"'{full.names[pairs[root_s]]}', the bone playing the {label}'s "
            f"root '{source.names[root_s]}'"
        )
    pair_arr = np.array(
        sorted((si, new_index[full.names[ti]]) for si, ti in pairs.items()), int
    ).reshape(-1, 2)
    tgt = tree
    # The rig answers to the names of the patch bones it plays (feet, thighs: found by the
    # core's name lookups, Skeleton.find, whatever the rig calls them).
    tgt.aliases = {source.names[si]: int(ti) for si, ti in pair_arr}
    t_by_s = dict(map(tuple, pair_arr))
    # Facing and hip heights from the paired legs.
    rs = {r: s_roles[r] for r in REQUIRED}
    rt = {r: t_by_s[s_roles[r]] for r in REQUIRED}
    lat_s = _lateral(source, rs["thigh.L"], rs["thigh.R"])
    lat_t = _lateral(tgt, rt["thigh.L"], rt["thigh.R"])
    ang = np.arctan2(lat_s[1], lat_s[0]) - np.arctan2(lat_t[1], lat_t[0])
    yaw = quat.to_matrix(quat.about_z(np.array(ang)))
    feet = ("foot.L", "toe.L", "foot.R", "toe.R")
    h_s = hip_height(source, source.root, [rs[r] for r in feet])
    h_t = hip_height(tgt, tgt.root, [rt[r] for r in feet])
    if h_s <= 1e-6 or h_t <= 1e-6:
        raise RetargetError(
            f"the hips are not above the feet in the rest pose of the {label} "
            f"skeleton or of the rig: cannot scale the root motion"
        )
    # Rest alignment of each paired bone: its direction to the next paired bone down.
    hs, ht = source.rest[:, :3, 3], tgt.rest[:, :3, 3]
    align = np.tile(np.eye(3), (len(pair_arr), 1, 1))
    for k, aim in enumerate(_aims(source, tgt, [tuple(p) for p in pair_arr.tolist()], lat_s)):
        if aim is None:
            continue
        si, ti = pair_arr[k]
        u = yaw @ (ht[aim[1]] - ht[ti])
        v = hs[aim[0]] - hs[si]
        align[k] = _rotation_between(u / np.linalg.norm(u), v / np.linalg.norm(v))
    unmapped = [source.names[i] for i in range(len(source.names)) if i not in t_by_s]
    return RigMap(
        source, tgt, pair_arr, h_t / h_s, float(floor), yaw, align, (s_conv, t_conv), unmapped
    )


def same_skeleton(a: Skeleton, b: Skeleton, tol: float = 1e-4) -> bool:
    """Whether two skeletons are the same (names, parents, rest matrices)."""
    return (
        a.names == b.names
        and np.array_equal(a.parents, b.parents)
        and np.allclose(a.rest, b.rest, atol=tol)
    )


_SEGMENT = re.compile(r"^(.*)\.\d{3}$")


def segment_parent(skel: Skeleton, j: int) -> int:
    """The parent of bone ``j``, skipping B-bone style segments of one limb (Rigify's
    ``DEF-shin.L.001`` is the lower half of ``DEF-shin.L``): the joint above ``j``."""
    p = int(skel.parents[j])
    while p >= 0:
        m = _SEGMENT.match(skel.names[p])
        if not (
            m and m.group(1) in skel.names and skel.names.index(m.group(1)) == int(skel.parents[p])
        ):
            return p
        p = int(skel.parents[p])
    return p


def retarget(
    clip: Clip, target: Skeleton, scale: float | None = None, name: str | None = None
) -> Clip:
    """The clip on another skeleton (another subject, or another naming convention).

    Each bone keeps its armature-space rotation relative to its (aligned) rest orientation
    (:func:`rig_map`'s rule, one place for clips, patches and plans); the root's motion is
    scaled by ``scale`` (default: the ratio of the skeletons' standing hip heights). Raises
    ValueError when the skeletons cannot be paired."""
    rm = rig_map(clip.skeleton, target)
    if scale is not None:
        rm.scale = float(scale)
    return rm.clip(clip, name)
