"""Two unit masses joined by a spring: the small test plant of the engine and recording tests."""

import numpy as np

from flexsat.dynamics.plant import Channel, Plant


class TwoCarts(Plant):
    """Two unit masses joined by a spring k, a force on each: x = [p1, p2, v1, v2]; outputs the
    2-wide ``position`` and the ``gap`` p2 − p1; energy kinetic plus spring."""

    inputs = (Channel("push", "N", size=2),)
    outputs = (Channel("position", "m", size=2), Channel("gap", "m"))
    recorded = ("position", "gap")
    noise_channels = ("gap",)

    def __init__(self, k=4.0):
        self.k = k

    @property
    def nx(self):
        return 4

    def linear_part(self):
        k = self.k
        A = np.zeros((4, 4))
        A[:2, 2:] = np.eye(2)
        A[2:, :2] = [[-k, k], [k, -k]]
        return A, np.vstack([np.zeros((2, 2)), np.eye(2)])

    def output_matrices(self, name):
        C = {
            "position": np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]]),
            "gap": np.array([[-1.0, 1.0, 0, 0]]),
            "speed": np.array([[0.0, 0, 1.0, 0]]),
        }[name]
        return C, np.zeros((len(C), self.n_inputs)), None

    def energy(self, x):
        p, v = x[..., :2], x[..., 2:]
        return 0.5 * (v**2).sum(-1) + 0.5 * self.k * (p[..., 1] - p[..., 0]) ** 2
