"""Our table file in pbrt-v4's `measured` against pbrt-v4's own layered
materials (`coatedconductor`, `coateddiffuse`: the stochastic random walk of
Guo et al. 2018) of the same parameters, in the same scene at the same spp.

Each side is rendered twice with different seeds: the difference of the two
renders of one side measures its noise, so the difference between the
sides can be read against the noise it would have if they agreed."""

import numpy as np

import pbrt4


EYE = (0.0, 0.8, 4.2)   # looking at the sphere's centre, the origin
FOV = 32.0              # degrees


def scene(material_line, resolution, spp, image_name):
    return """# Peer comparison (shims/pbrt-v4/check/peer.py)
LookAt %g %g %g  0 0 0  0 1 0
Camera "perspective" "float fov" [ %g ]
%sWorldBegin
LightSource "infinite" "spectrum L" [ 300 1  900 1 ] "float scale" [ 0.25 ]
LightSource "distant" "point3 from" [ 2 3 4 ] "point3 to" [ 0 0 0 ]
    "spectrum L" [ 300 1  900 1 ] "float scale" [ 3 ]
%s
Shape "sphere" "float radius" [ 1 ]
""" % (EYE + (FOV, pbrt4.film(resolution, spp, image_name), material_line))


def sphere_mask(resolution):
    """Pixels wholly on the unit sphere: the camera looks at its centre, so
    the silhouette is the circle of rays within asin(1 / |eye|) of the
    axis; a pixel counts when its four corners are inside."""
    edge = np.tan(np.radians(FOV / 2)) * np.linspace(-1.0, 1.0, resolution + 1)
    r = np.hypot(edge[:, None], edge[None, :])
    inside = np.arctan(r) < np.arcsin(1.0 / np.linalg.norm(EYE))
    return inside[:-1, :-1] & inside[1:, :-1] & inside[:-1, 1:] & inside[1:, 1:]


def statistics(ours, theirs):
    """ours, theirs: two renders each (same scene, different seeds). Over
    the pixels wholly on the sphere:
    rmse: relative RMSE between the two sides' means;
    noise: the RMSE that difference would have from noise alone;
    bias: relative difference of the mean pixel values, and its standard
    error; noise_ours / noise_theirs: relative RMSE of one render."""
    mask = sphere_mask(ours[0].shape[0])
    a = [x[mask] for x in ours]
    b = [x[mask] for x in theirs]
    scale = 0.5 * (a[0] + a[1] + b[0] + b[1]).mean() / 2.0
    noise_a = np.sqrt(np.mean((a[0] - a[1]) ** 2) / 2.0) / scale
    noise_b = np.sqrt(np.mean((b[0] - b[1]) ** 2) / 2.0) / scale
    mean_a, mean_b = 0.5 * (a[0] + a[1]), 0.5 * (b[0] + b[1])
    rmse = np.sqrt(np.mean((mean_a - mean_b) ** 2)) / scale
    noise = np.sqrt((noise_a ** 2 + noise_b ** 2) / 2.0)
    pix_a, pix_b = mean_a.mean(axis=1), mean_b.mean(axis=1)
    bias = pix_a.mean() / pix_b.mean() - 1.0
    bias_err = np.sqrt(noise_a ** 2 + noise_b ** 2) / np.sqrt(2.0 * pix_a.size) * \
        scale / pix_b.mean()
    return {"pixels": int(mask.sum()), "rmse": rmse, "noise": noise, "bias": bias,
            "bias_err": bias_err, "noise_ours": noise_a, "noise_theirs": noise_b}
