"""Draw docs/conventions.png: the two direction conventions of ll_bsdf.h.

Left, the layer convention (ll_bsdf_eval, ll_layer_eval): mu_i and mu_o are
cosines of directions of TRAVEL, positive travelling down; phi_d is the
azimuth between the two directions of travel. Right, the renderer convention
(the *_dir calls): wo toward the viewer and wi toward the light, both
pointing away from the surface, and the mapping between the two.

    python3 docs/conventions.py docs/conventions.png

Needs numpy and matplotlib (the tests' virtual environment has both).
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402
from matplotlib.patches import FancyArrowPatch  # noqa: E402


class Arrow3D(FancyArrowPatch):
    """An arrow between two 3-D points, drawn after projection."""

    def __init__(self, a, b, **kw):
        super().__init__((0, 0), (0, 0), **kw)
        self._a, self._b = np.asarray(a, float), np.asarray(b, float)

    def do_3d_projection(self, renderer=None):
        xs, ys, zs = proj3d.proj_transform(*np.c_[self._a, self._b], self.axes.M)
        self.set_positions((xs[0], ys[0]), (xs[1], ys[1]))
        return np.min(zs)


def direction(theta, phi):
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def scene(ax, title):
    """The upper hemisphere as a wire frame, the surface as a disc, the normal."""
    u = np.linspace(0, 2 * np.pi, 60)
    for t in np.radians([30, 60]):
        ax.plot(np.sin(t) * np.cos(u), np.sin(t) * np.sin(u), np.full_like(u, np.cos(t)),
                color="0.85", lw=0.6)
    v = np.linspace(0, np.pi / 2, 30)
    for p in np.radians(np.arange(0, 360, 45)):
        ax.plot(np.sin(v) * np.cos(p), np.sin(v) * np.sin(p), np.cos(v), color="0.85", lw=0.6)
    r, a = np.meshgrid(np.linspace(0, 1, 2), u)
    ax.plot_surface(r * np.cos(a), r * np.sin(a), 0 * r, color="#d9c58a", alpha=0.35,
                    linewidth=0)
    ax.plot(np.cos(u), np.sin(u), 0 * u, color="#8a7a45", lw=1)
    ax.add_artist(Arrow3D((0, 0, 0), (0, 0, 1.25), arrowstyle="-|>", mutation_scale=12,
                          color="0.35", lw=1))
    ax.text(0.03, 0, 1.3, "z = normal (top side)", color="0.35", fontsize=8)
    ax.text(1.0, -0.55, -0.05, "surface", color="#8a7a45", fontsize=8)
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 1)
    ax.set_zlim(-0.2, 1.3)
    ax.set_box_aspect((1, 1, 0.75), zoom=1.45)
    ax.view_init(elev=22, azim=-62)
    ax.set_axis_off()
    ax.set_title(title, fontsize=11)


def arrow(ax, a, b, color, label, at, **kw):
    ax.add_artist(Arrow3D(a, b, arrowstyle="-|>", mutation_scale=16, color=color, lw=2, **kw))
    ax.text(*at, label, color=color, fontsize=10)


def azimuth_arc(ax, phi0, phi1, radius, color, label):
    p = np.linspace(phi0, phi1, 40)
    ax.plot(radius * np.cos(p), radius * np.sin(p), 0 * p, color=color, lw=1.5)
    m = 0.5 * (phi0 + phi1)
    ax.text(1.12 * radius * np.cos(m), 1.12 * radius * np.sin(m), 0.02, label, color=color,
            fontsize=10)


def zenith_arc(ax, d, color, label):
    """The angle between the normal and the unit vector d (above the surface)."""
    t = np.arccos(d[2])
    phi = np.arctan2(d[1], d[0])
    s = np.linspace(0, t, 20)
    pts = np.array([direction(x, phi) for x in s]) * 0.35
    ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], color=color, lw=1.2)
    ax.text(*(direction(0.5 * t, phi) * 0.36 + (0, 0, 0.1)), label, color=color, fontsize=9,
            ha="right" if np.cos(phi) < 0 else "left")


def main(path):
    blue, red, green = "#1f5fa8", "#b8322a", "#2f7d32"
    theta_a, phi_a = np.radians(40), np.radians(200)   # one direction: light / view
    theta_b, phi_b = np.radians(55), np.radians(-25)   # the other
    up_a, up_b = direction(theta_a, phi_a), direction(theta_b, phi_b)

    fig = plt.figure(figsize=(12, 6.2), dpi=110)

    # Layer convention: light travels down along -up_a (mu_i = cos theta_a > 0)
    # and leaves travelling up along up_b (mu_o = -cos theta_b < 0). phi_d is
    # the azimuth between the two directions of travel: that of -up_a is phi_a + pi.
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    scene(ax, "layer convention: directions of travel\nll_bsdf_eval(mu_i, mu_o, phi_d), ll_layer_eval")
    arrow(ax, 1.15 * up_a, (0, 0, 0), blue, "light arrives,\ntravelling down\nmu_i > 0",
          1.2 * up_a + (0, 0, 0.05))
    arrow(ax, (0, 0, 0), 1.1 * up_b, red, "light leaves,\ntravelling up\nmu_o < 0",
          1.15 * up_b + (0, 0, 0.05))
    zenith_arc(ax, up_a, blue, "acos mu_i")
    zenith_arc(ax, up_b, red, "acos(-mu_o)")
    travel_a = phi_a + np.pi                      # azimuth of the incoming travel
    ax.plot([0, 0.6 * np.cos(travel_a)], [0, 0.6 * np.sin(travel_a)], [0, 0], color=blue,
            lw=1, ls="--")
    ax.plot([0, 0.6 * np.cos(phi_b)], [0, 0.6 * np.sin(phi_b)], [0, 0], color=red, lw=1, ls="--")
    lo, hi = sorted([phi_b, travel_a - 2 * np.pi])
    azimuth_arc(ax, lo, hi, 0.5, green, "phi_d")
    fig.text(0.04, 0.02, "mirror direction: mu_o = -mu_i, phi_d = 0\n"
              "transmission: mu_i and mu_o of the same sign\n"
              "(both panels show the same pair of directions)",
              fontsize=9)

    # Renderer convention: both vectors point away from the surface.
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    scene(ax, "renderer convention (pbrt's BxDF::f(wo, wi))\nll_bsdf_eval_dir(wo, wi), _pdf_dir, _sample_dir")
    arrow(ax, (0, 0, 0), 1.1 * up_a, blue, "wo: toward the viewer", 1.15 * up_a + (0, 0, 0.05))
    arrow(ax, (0, 0, 0), 1.1 * up_b, red, "wi: toward the light\n(the sampled one)",
          1.15 * up_b + (0, 0, 0.05))
    zenith_arc(ax, up_a, blue, "acos wo.z")
    zenith_arc(ax, up_b, red, "acos wi.z")
    fig.text(0.54, 0.02, "evaluated as the layer convention at\n"
              "  mu_i = wo.z / |wo|,   mu_o = -wi.z / |wi|,\n"
              "  cos phi_d = -(wo.x wi.x + wo.y wi.y) / (|wo.xy| |wi.xy|)\n"
              "i.e. light travelling along -wo, leaving along wi (reciprocity)",
              fontsize=9, family="monospace")

    fig.subplots_adjust(left=0.0, right=1.0, top=0.9, bottom=0.14, wspace=0.0)
    fig.savefig(path)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/conventions.png")
