"""The materials of the checks, each said three ways: the material language
(what llbuild turns into our table file), our layers per wavelength (the
furnace's expected albedo, through the Python package), and, for the peer
comparison, pbrt-v4's own layered material of the same parameters.

Conventions that must agree:
- roughness: pbrt-v4's `remaproughness` is turned off, so its
  `interface.roughness` / `conductor.roughness` is the GGX alpha itself
  (with the default remapping, alpha = sqrt(roughness));
- the conductor under a coat: pbrt-v4 divides the metal's eta and k by the
  coat's index, as the material language does for `conductor` below
  `dielectric`;
- the metal's spectrum: pbrt-v4 is given the very numbers of data/ior/
  (an inline `spectrum`), so both sides see the same gold;
- pbrt-v4's `thickness` is the optical thickness of the medium between the
  two interfaces (its transmittance is exp(-thickness / |cos|)); with
  `albedo` 0 the medium absorbs, so a plain coat is `thickness` 0;
- our interfaces are built with `compensate=0`: pbrt-v4's interfaces are
  single-scattering microfacet BSDFs.
"""

import numpy as np

import spectra


def gold_spectrum_param(name, scale=1.0):
    lam, n = spectra.measured_index("Au")
    keep = (lam >= 300) & (lam <= 900)
    values = n.real if name == "eta" else n.imag
    pairs = " ".join("%.4f %.6f" % (l, v * scale) for l, v in zip(lam[keep], values[keep]))
    return '"spectrum conductor.%s" [ %s ]' % (name, pairs)


class Material:
    def __init__(self, name, layers_text, stack, pbrt_native=None):
        self.name = name
        self.layers_text = layers_text   # material language
        self.stack = stack               # list of ("kind", parameters) from the top
        self.pbrt_native = pbrt_native   # pbrt-v4 material line, or None


def _gold(alpha, dist="beckmann", compensate=1):
    return ("conductor", {"metal": "Au", "alpha": alpha, "dist": dist, "compensate": compensate})


def _coat(alpha, dist="beckmann", compensate=1):
    return ("dielectric", {"eta": 1.5, "alpha": alpha, "dist": dist, "compensate": compensate})


def furnace_materials():
    """Untextured opaque materials with no RGB albedos (their spectra are
    the measured ones and constants): the furnace checks the spectral file
    end to end."""
    return [
        Material("gold", "conductor eta=Au alpha=0.2\n", [_gold(0.2)]),
        Material("coated-gold",
                 "dielectric eta=1.5 alpha=0.1\nconductor eta=Au alpha=0.1\n",
                 [_coat(0.1), _gold(0.1)]),
        Material("grey-dust-on-gold",
                 "medium albedo=0.7 g=0.6 tau=0.4\nconductor eta=Au alpha=0.2\n",
                 [("medium", {"albedo": 0.7, "g": 0.6, "tau": 0.4}), _gold(0.2)]),
    ]


def peer_materials(alphas=(0.1, 0.3)):
    out = []
    for a in alphas:
        ggx = "dist=ggx compensate=0"
        # the bare conductor: pbrt-v4's `conductor`, no layering, so that a
        # difference of the interface model shows apart from the adding
        out.append(Material(
            "conductor-a%g" % a,
            "conductor eta=Au alpha=%g %s\n" % (a, ggx),
            [_gold(a, "ggx", 0)],
            'Material "conductor" "float roughness" [ %g ] "bool remaproughness" false\n'
            '    %s\n    %s\n'
            % (a, gold_spectrum_param("eta").replace("conductor.", ""),
               gold_spectrum_param("k").replace("conductor.", ""))))
        out.append(Material(
            "coatedconductor-a%g" % a,
            "dielectric eta=1.5 alpha=%g %s\nconductor eta=Au alpha=%g %s\n" % (a, ggx, a, ggx),
            [_coat(a, "ggx", 0), _gold(a, "ggx", 0)],
            'Material "coatedconductor" "float interface.eta" [ 1.5 ]\n'
            '    "float interface.roughness" [ %g ] "float conductor.roughness" [ %g ]\n'
            '    %s\n    %s\n'
            '    "float thickness" [ 0 ] "bool remaproughness" false\n'
            '    "integer maxdepth" [ 100 ] "integer nsamples" [ 8 ]\n'
            % (a, a, gold_spectrum_param("eta"), gold_spectrum_param("k"))))
        out.append(Material(
            "coateddiffuse-a%g" % a,
            "dielectric eta=1.5 alpha=%g %s\ndiffuse albedo=0.5\n" % (a, ggx),
            [_coat(a, "ggx", 0), ("diffuse", {"albedo": 0.5})],
            'Material "coateddiffuse" "float roughness" [ %g ] "float eta" [ 1.5 ]\n'
            '    "rgb reflectance" [ 0.5 0.5 0.5 ] "float thickness" [ 0 ]\n'
            '    "bool remaproughness" false "integer maxdepth" [ 100 ] "integer nsamples" [ 8 ]\n'
            % a))
    out.append(Material(
        "coateddiffuse-medium-a0.3",
        "dielectric eta=1.5 alpha=0.3 dist=ggx compensate=0\n"
        "medium albedo=0.8 g=0.5 tau=0.5\ndiffuse albedo=0.5\n",
        [_coat(0.3, "ggx", 0), ("medium", {"albedo": 0.8, "g": 0.5, "tau": 0.5}),
         ("diffuse", {"albedo": 0.5})],
        'Material "coateddiffuse" "float roughness" [ 0.3 ] "float eta" [ 1.5 ]\n'
        '    "rgb reflectance" [ 0.5 0.5 0.5 ] "float thickness" [ 0.5 ]\n'
        '    "rgb albedo" [ 0.8 0.8 0.8 ] "float g" [ 0.5 ]\n'
        '    "bool remaproughness" false "integer maxdepth" [ 100 ] "integer nsamples" [ 8 ]\n'))
    return out


def layers_at(ll, material, wavelength, nodes=300, orders=1):
    """Our stack at one wavelength; order 0 only by default (the albedo
    needs no more)."""
    mu, w = ll.quad.gaussLobatto(nodes)
    above = 1.0   # absolute index above the current interface (a named metal's is absolute)
    result = None
    for kind, p in material.stack:
        layer = ll.Layer(mu, w, orders)
        if kind == "dielectric":
            # the language's dielectric eta is relative to what is above it
            layer.setMicrofacet(p["eta"], p["alpha"], conserveEnergy=bool(p["compensate"]),
                                distribution=p["dist"])
            above *= p["eta"]
        elif kind == "conductor":
            n = spectra.index_at(p["metal"], wavelength)
            layer.setMicrofacet(complex(n) / above, p["alpha"],
                                conserveEnergy=bool(p["compensate"]), distribution=p["dist"])
        elif kind == "medium":
            layer.setHenyeyGreenstein(p["albedo"], p["g"])
            layer.expand(p["tau"])
        elif kind == "diffuse":
            layer.setDiffuse(p["albedo"])
        else:
            raise ValueError(kind)
        result = layer if result is None else ll.Layer.add(result, layer)
    return result
