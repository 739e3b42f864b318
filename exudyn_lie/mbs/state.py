"""Plain views of the body states handed to Python callbacks and returned to users."""
from dataclasses import dataclass

import numpy as np

from .codes import BODY_TWIST


@dataclass
class BodyStates:
    """Configuration and velocity of all bodies at one instant.

    ``R`` (nb,3,3) body->world, ``r`` (nb,3) frame origins, ``omega`` (nb,3) body-fixed
    angular velocities, ``vel`` (nb,3) world velocities of the frame origins."""
    t: float
    R: np.ndarray
    r: np.ndarray
    omega: np.ndarray
    vel: np.ndarray


def twist_to_world_velocity(gid, R, V):
    """(omega body, world velocity of the frame origin) from the group velocity."""
    omega = V[:, :3].copy()
    vel = V[:, 3:].copy()
    se3 = BODY_TWIST[np.asarray(gid)]
    if np.any(se3):
        vel[se3] = np.einsum("nij,nj->ni", R[se3], V[se3, 3:])
    return omega, vel


def world_velocity_to_twist(gid, R, omega, vel):
    """Group velocity from body-fixed omega and world frame-origin velocity."""
    V = np.zeros((len(gid), 6))
    V[:, :3] = omega
    V[:, 3:] = vel
    se3 = BODY_TWIST[np.asarray(gid)]
    if np.any(se3):
        V[se3, 3:] = np.einsum("nji,nj->ni", R[se3], vel[se3])
    return V
