"""A simulated studio apartment for vision-and-language navigation: furniture geometry and collisions,
a ray-cast RGB-D camera, a top-down map, and a grid planner for shortest routes through goal regions."""

from lerobot_contrast.domains.vln.apartment.camera import CameraSpec, RayCaster
from lerobot_contrast.domains.vln.apartment.furniture import CATALOG, STUDIO, Furniture, furniture_for
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room, clearance
from lerobot_contrast.domains.vln.apartment.planner import Grid, Route, hausdorff, resample
from lerobot_contrast.domains.vln.apartment.topdown import render_map
from lerobot_contrast.domains.vln.apartment.world import COLLISION_MODES, Apartment, wrap_angle

__all__ = [
    "CATALOG",
    "COLLISION_MODES",
    "STUDIO",
    "Apartment",
    "CameraSpec",
    "Footprints",
    "Furniture",
    "Grid",
    "RayCaster",
    "Room",
    "Route",
    "clearance",
    "furniture_for",
    "hausdorff",
    "render_map",
    "resample",
    "wrap_angle",
]
