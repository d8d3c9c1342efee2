"""MJCF of a navigation world: obstacles, floor appearance and lights, for Plant(scene_xml=...).

    scene = build_scene(world)                     # world: sim/world.py World
    plant = Plant(robot, params, world.start_rad, scene_xml=scene.scene_xml,
                  assets_xml=scene.assets_xml)

Obstacles are static geoms named obstacle_<k> (k = index in the world file) with contype 2 and
conaffinity 1: the links (contype 1) touch them, the floor (contype 2, conaffinity 1) does not.
The floor texture is drawn on a visual-only plane `floor_visual` 0.2 mm above the physical floor
(no contacts; the camera's segmentation counts both as ground).

Appearance (textures, colours, light) is separate from the world so that the classifier's training
renders can vary it (`random_appearance(rng)`) over the same geometry. A world whose floor_texture is
one of ODOMETRY_FLOOR_TEXTURES looks like the odometry room (ODOMETRY_APPEARANCE): random dots of a
few cm on the floor and the obstacles, lit without shadows, so that the visual odometry (nav runs'
pose source vo) finds features wherever the head camera turns.
"""
import math
from dataclasses import dataclass, field, replace
from typing import List, Optional, Tuple

import numpy as np

from .mjcf import OVERHEAD_LIGHT
from .world import SimWorld, WorldSpec
from .world_file import FLOOR_TEXTURES, ODOMETRY_FLOOR_TEXTURES, WORLD_FLOOR_TEXTURES, World

#: floor texture presets: (MuJoCo builtin, mark, rgb1, rgb2, random fraction, texrepeat per m)
FLOOR_PRESETS = {
    "plain": ("flat", "none", (0.55, 0.55, 0.52), (0.55, 0.55, 0.52), 0.0, 1.0),
    "checker": ("checker", "none", (0.45, 0.45, 0.48), (0.62, 0.62, 0.60), 0.0, 2.0),
    "carpet": ("flat", "random", (0.42, 0.30, 0.25), (0.60, 0.50, 0.40), 0.35, 4.0),
    "tiles": ("checker", "edge", (0.70, 0.68, 0.62), (0.66, 0.64, 0.58), 0.0, 3.0),
    "concrete": ("flat", "random", (0.50, 0.50, 0.50), (0.70, 0.70, 0.68), 0.25, 6.0),
    # the odometry room's floor (vo_room): dark dots on half the texels, a texel 2.4 cm
    "dots": ("flat", "random", (0.55, 0.50, 0.45), (0.42, 0.33, 0.33), 0.5, 1.0 / (512 * 0.024)),
}
assert set(FLOOR_PRESETS) == set(WORLD_FLOOR_TEXTURES)
OBSTACLE_MARKS = ("none", "random", "edge", "cross")


@dataclass
class Appearance:
    """How a world looks: floor texture, obstacle colours/textures, light."""
    floor: str = "plain"
    floor_rgb: Optional[Tuple[Tuple[float, float, float], Tuple[float, float, float]]] = None
    obstacle_rgb: List[Tuple[float, float, float]] = field(default_factory=list)
    obstacle_mark: str = "none"
    light_diffuse: float = 0.7
    light_dir: Tuple[float, float, float] = (0.3, 0.2, -1.0)
    obstacle_texel_m: Optional[float] = None     # None: the texture repeats 4 times per m (texels of 2 mm)
    obstacle_mark_rgb: Optional[Tuple[float, float, float]] = None   # None: from the obstacle's colour
    obstacle_mark_fraction: float = 0.3
    shadows: bool = True                         # False: lit like the odometry room (diffuse_lights)

    def obstacle_colour(self, k: int) -> Tuple[float, float, float]:
        if self.obstacle_rgb:
            return self.obstacle_rgb[k % len(self.obstacle_rgb)]
        return (0.75, 0.35, 0.15)


#: how a world with an odometry floor looks (see the module's docstring); measured on a 5 m corridor,
#: 20 s, seed 0: tracking never lost, against 92 % of the time on carpet with the overhead light
ODOMETRY_APPEARANCE = Appearance(floor="dots", obstacle_mark="random", obstacle_texel_m=0.03,
                                 obstacle_mark_rgb=(0.15, 0.15, 0.3), obstacle_mark_fraction=0.5, shadows=False)


def diffuse_lights() -> List[str]:
    """Lit like a lab under diffuse ceiling lights (many sources): the robot casts no hard shadow that
    moves with it into its head camera's view, as a single shadow-casting light makes it do (strong
    false features for the odometry). No light casts shadows, and a scene lit by them has no
    sim/mjcf.OVERHEAD_LIGHT. One directional light towards each side (a single one leaves the walls it
    skims dark: too few ORB features there) and some ambient light.

    MuJoCo sums the ambient and diffuse light of the lights without shadows and clamps the sum at
    full, so the floor under these already shows its texture's own colours: brighter or more such
    lights add nothing to it (a 0.5 grey plane: 104 grey levels under one light of diffuse 0.7, 127
    under 1.0 or 1.5). A shadow-casting light is drawn in a pass of its own added on top (142 under
    1.0): the extra brightness and contrast the odometry room had with OVERHEAD_LIGHT."""
    return [f'    <light name="scene_light_{k}" dir="{_v(d)}" directional="true" diffuse="0.35 0.35 0.35" '
            f'ambient="{"0.25 0.25 0.25" if k == 0 else "0 0 0"}" castshadow="false"/>'
            for k, d in enumerate([(1, 0.2, -1), (-1, -0.2, -1), (-0.2, 1, -1), (0.2, -1, -1)])]


def random_appearance(rng: np.random.Generator) -> Appearance:
    """A random floor texture, obstacle colours and marks, and light (for classifier training)."""
    floor = str(rng.choice(FLOOR_TEXTURES))
    base = rng.uniform(0.25, 0.75, 3)
    floor_rgb = (tuple(base), tuple(np.clip(base + rng.uniform(-0.15, 0.15, 3), 0, 1)))
    colours = [tuple(rng.uniform(0.05, 0.95, 3)) for _ in range(4)]
    d = (rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), -1.0)
    return Appearance(floor=floor, floor_rgb=floor_rgb, obstacle_rgb=colours,
                      obstacle_mark=str(rng.choice(OBSTACLE_MARKS)),
                      light_diffuse=float(rng.uniform(0.35, 0.9)), light_dir=d)


@dataclass
class Scene:
    scene_xml: str
    assets_xml: str


def _v(values) -> str:
    return " ".join(f"{float(x):.6g}" for x in values)


def build_scene(world: World, appearance: Optional[Appearance] = None,
                floor_size_m: float = 30.0) -> Scene:
    app = appearance or (ODOMETRY_APPEARANCE if world.floor_texture in ODOMETRY_FLOOR_TEXTURES
                         else Appearance(floor=world.floor_texture))
    builtin, mark, rgb1, rgb2, rnd, repeat = FLOOR_PRESETS[app.floor]
    if app.floor_rgb is not None:
        rgb1, rgb2 = app.floor_rgb
    assets = [
        f'    <texture name="floor_tex" type="2d" builtin="{builtin}" mark="{mark}" '
        f'rgb1="{_v(rgb1)}" rgb2="{_v(rgb2)}" markrgb="{_v(np.clip(np.asarray(rgb2) * 0.6, 0, 1))}" '
        f'random="{rnd:.3g}" width="512" height="512"/>',
        f'    <material name="floor_mat" texture="floor_tex" texrepeat="{repeat:.6g} {repeat:.6g}" '
        f'texuniform="true" reflectance="0"/>',
    ]
    half = 0.5 * floor_size_m
    # the model's overhead light (casting shadows) as in a model without a scene, and the appearance's
    scene = [
        f'    {OVERHEAD_LIGHT}',
        f'    <light name="scene_light" dir="{_v(app.light_dir)}" directional="true" '
        f'diffuse="{_v([app.light_diffuse] * 3)}" castshadow="false"/>',
    ] if app.shadows else diffuse_lights()
    repeat = 4.0 if app.obstacle_texel_m is None else 1.0 / (128 * app.obstacle_texel_m)
    scene += [
        f'    <geom name="floor_visual" type="plane" pos="{_v(world.start[:2])} 0.0002" '
        f'size="{half:.6g} {half:.6g} 0.1" material="floor_mat" contype="0" conaffinity="0"/>',
    ]
    for k, ob in enumerate(world.obstacles):
        colour = app.obstacle_colour(k)
        mark_rgb = app.obstacle_mark_rgb
        if mark_rgb is None:
            mark_rgb = np.clip(np.asarray(colour) * 0.5 + 0.2, 0, 1)
        mat = f"obstacle_mat_{k}"
        assets += [
            f'    <texture name="obstacle_tex_{k}" type="2d" builtin="flat" mark="{app.obstacle_mark}" '
            f'rgb1="{_v(colour)}" rgb2="{_v(colour)}" '
            f'markrgb="{_v(mark_rgb)}" random="{app.obstacle_mark_fraction:.3g}" width="128" height="128"/>',
            f'    <material name="{mat}" texture="obstacle_tex_{k}" texrepeat="{repeat:.6g} {repeat:.6g}" '
            f'texuniform="true"/>',
        ]
        common = f'name="obstacle_{k}" contype="2" conaffinity="1" condim="3" material="{mat}"'
        if ob.kind == "cylinder":
            scene.append(f'    <geom {common} type="cylinder" pos="{_v((ob.x_m, ob.y_m, ob.height_m / 2))}" '
                         f'size="{ob.radius_m:.6g} {ob.height_m / 2:.6g}"/>')
        else:
            sx, sy, sz = ob.size_m
            yaw = math.radians(ob.yaw_deg)
            scene.append(f'    <geom {common} type="box" pos="{_v((ob.x_m, ob.y_m, sz / 2))}" '
                         f'size="{_v((sx / 2, sy / 2, sz / 2))}" '
                         f'quat="{_v((math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)))}"/>')
    return Scene("\n".join(scene) + "\n", "\n".join(assets) + "\n")


def world_plant_fields(world: World, flat_belly_fraction: Optional[float]) -> dict:
    """sim.world.WorldSpec fields that put a nav world in the plant: its obstacles and floor, base_link
    at the world's start, the nav runs' plant option (config/nav.yaml plant:)."""
    scene = build_scene(world)
    return {"scene_xml": scene.scene_xml, "assets_xml": scene.assets_xml, "start_base": world.start_rad,
            "flat_belly_fraction": flat_belly_fraction}


#: the visual odometry's room (sim_node ~feedback vo without a world): walls this far from the room's
#: centre on each side and this high, so that the level head camera sees texture wherever it turns.
#: The star mission (1.5 m around the odometry frame's origin) flown from the room's centre keeps
#: the centre of mass 1.7 m and COBRA's body (0.8 m from its centre of mass) 0.86 m from every wall.
VO_ROOM_HALF_M, VO_ROOM_HEIGHT_M = 3.2, 2.0
_VO_WALL_COLOURS = [((0.8, 0.7, 0.3), (0.2, 0.1, 0.4)), ((0.3, 0.6, 0.8), (0.6, 0.1, 0.1)),
                    ((0.7, 0.4, 0.6), (0.1, 0.3, 0.1)), ((0.6, 0.8, 0.5), (0.3, 0.2, 0.5))]


def vo_room(centre_xy: Tuple[float, float] = (0.0, 0.0), half_m: float = VO_ROOM_HALF_M) -> Scene:
    """An obstacle-free room for the visual odometry: a random-dot floor (texels of about 2.4 cm) and
    four random-dot walls (about 5 cm), half_m from centre_xy, lit without shadows. The walls are
    obstacles to the contacts' count (obstacle_<k>)."""
    if not half_m > 0:
        raise ValueError(f"vo_room: half_m must be > 0, got {half_m!r}")
    cx, cy = (float(v) for v in centre_xy)
    half, h = float(half_m), 0.5 * VO_ROOM_HEIGHT_M
    assets = ['    <texture name="floor_tex" type="2d" builtin="flat" mark="random" random="0.5" '
              'rgb1="0.55 0.5 0.45" rgb2="0.55 0.5 0.45" markrgb="0.25 0.2 0.2" width="256" height="256"/>',
              '    <material name="floor_mat" texture="floor_tex" texrepeat="1 1"/>']
    scene = diffuse_lights()
    scene += [f'    <geom name="floor_visual" type="plane" pos="{_v((cx, cy))} 0.0002" '
              f'size="{half:.6g} {half:.6g} 0.1" material="floor_mat" contype="0" conaffinity="0"/>']
    walls = [((cx + half, cy), (0.02, half)), ((cx - half, cy), (0.02, half)), ((cx, cy + half), (half, 0.02)),
             ((cx, cy - half), (half, 0.02))]
    for k, (((x, y), (sx, sy)), (rgb, mark)) in enumerate(zip(walls, _VO_WALL_COLOURS)):
        assets += [f'    <texture name="wall_tex_{k}" type="2d" builtin="flat" mark="random" random="0.5" '
                   f'rgb1="{_v(rgb)}" rgb2="{_v(rgb)}" markrgb="{_v(mark)}" width="128" height="128"/>',
                   f'    <material name="wall_mat_{k}" texture="wall_tex_{k}" texrepeat="1 1"/>']
        scene.append(f'    <geom name="obstacle_{k}" type="box" pos="{_v((x, y, h))}" size="{_v((sx, sy, h))}" '
                     f'material="wall_mat_{k}" contype="2" conaffinity="1"/>')
    return Scene("\n".join(scene) + "\n", "\n".join(assets) + "\n")


def vo_room_around_camera(spec: WorldSpec, half_m: float = VO_ROOM_HALF_M) -> Scene:
    """vo_room centred on the odometry camera's (camera_link's) position at the start of the world
    `spec` describes (its start, robot, calibration; its scene is ignored): the odometry frame, and
    with it a mission flown in it, starts there."""
    probe = SimWorld(replace(spec, scene_xml="", assets_xml="", sensors=("mocap", "imu"), mission=""))
    T = probe.plant.frame_transform("head_link") @ probe.camera_in_head
    return vo_room((float(T[0, 3]), float(T[1, 3])), half_m)
