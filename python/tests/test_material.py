"""Material: parsing the material language and building it, in memory and to
a file, with progress reports, cancellation and parse errors."""

import threading

import numpy as np
import pytest

import layerlab as ll

PLASTIC = """\
# a clear coat over a diffuse base
dielectric eta=1.5 alpha=0.3
diffuse    albedo=0.5
"""


def test_parse_and_build_layers_in_memory():
    material = ll.Material.parse(PLASTIC, "plastic.layers")
    assert len(material) == 2
    assert repr(material) == "Material[words=2]"
    n, m, channels = material.resolution(nodes=40, orders=20)
    assert (n, m, channels) == (40, 20, 1)
    # Chosen by a tolerance: a looser one never needs more nodes here
    # (docs/method.md, "Resolution"); a tolerance below 0.001 is refused.
    loose, tight = material.resolution(tolerance=0.05), material.resolution(tolerance=0.01)
    assert loose[0] <= tight[0] and loose[2] == tight[2] == 1
    with pytest.raises(ll.InvalidArgumentError):
        material.resolution(tolerance=1e-4)
    est = material.estimate(nodes=40, orders=20)
    assert (est["nodes"], est["orders"], est["channels"]) == (40, 20, 1)
    assert est["layers_built"] == 2 and est["additions"] == 1 and est["doublings"] == 0
    assert est["peak_bytes"] > 0 and est["file_bytes"] > 0
    # A coat over a diffuse base: one interface's pairs, one adding, the writing.
    assert est["work"]["dielectric_pairs"] > 0 and est["work"]["conductor_pairs"] == 0
    assert est["work"]["add_entries"] > 0 and est["work"]["stored_values"] > 0
    layers, header = material.build_layers(nodes=40, orders=20)
    assert len(layers) == 1 and layers[0].resolution == 40 and layers[0].fourierOrders == 20
    assert header["eta"] == 1.0  # an opaque stack
    r, t = layers[0].albedo(0.8)
    # A coated white-ish diffuser: less than the bare albedo, no transmission.
    assert 0.2 < r < 0.5 and abs(t) < 1e-9


def test_built_layers_equal_a_python_built_stack():
    layers, _ = ll.Material.parse(PLASTIC).build_layers(nodes=40, orders=20)
    coat = ll.Layer(*ll.quad.gaussLobatto(40), 20)
    coat.setMicrofacet(eta=1.5, alpha=0.3)
    base = ll.Layer(*ll.quad.gaussLobatto(40), 20)
    base.setDiffuse(0.5)
    base.addToTop(coat)
    for mu in (0.2, 0.5, 0.9):
        assert layers[0].albedo(mu)[0] == pytest.approx(base.albedo(mu)[0], rel=1e-2)


def test_rgb_material_and_build_to_file(tmp_path):
    material = ll.Material.parse("dielectric eta=1.5 alpha=0.2\ndiffuse albedo=0.2,0.5,0.8\n")
    seen = []
    storage = material.build(tmp_path / "rgb.bsdf", nodes=30, orders=10,
                             progress=lambda fraction, stage: seen.append((fraction, stage)))
    assert isinstance(storage, ll.BSDFStorage) and storage.channelCount == 3
    assert seen and all(0.0 <= f <= 1.0 for f, _ in seen)
    assert all(isinstance(stage, str) and stage for _, stage in seen)
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions)
    rgb = storage.eval(0.7, -0.7)
    assert rgb[0] < rgb[1] < rgb[2]
    layers, header = material.build_layers(nodes=30, orders=10)
    assert len(layers) == 3
    again = material.write(tmp_path / "again.bsdf", layers)
    assert again.channelCount == 3 and again.eta == header["eta"]
    np.testing.assert_allclose(again.eval(0.7, -0.7), rgb, rtol=1e-6)
    with pytest.raises(TypeError):
        material.write(tmp_path / "bad.bsdf", [layers[0], "x", layers[2]])


def test_parse_errors_name_line_and_column(tmp_path):
    with pytest.raises(ll.ParseError) as e:
        ll.Material.parse("dielectric eta=1.5 alpha=0.1\nshiny albedo=0.5\n", "bad.layers")
    assert isinstance(e.value, ValueError) and e.value.status == 7
    assert "bad.layers:2:" in str(e.value)
    with pytest.raises(ll.ParseError):
        ll.Material.parse("diffuse albedo=0.5\ndielectric eta=1.5 alpha=0.1\n")  # opaque on top
    path = tmp_path / "m.layers"
    path.write_text("conductor eta=Au alpha=0\n")
    with pytest.raises(ll.ParseError) as e:
        ll.Material.parse_file(path)
    assert "m.layers:1:" in str(e.value)
    with pytest.raises(OSError):
        ll.Material.parse_file(tmp_path / "missing.layers")
    with pytest.raises(TypeError):
        ll.Material(None)


def test_cancel_flag_and_raising_progress_leave_no_file(tmp_path):
    material = ll.Material.parse(PLASTIC)
    flag = ll.CancelFlag()
    flag.set()
    with pytest.raises(ll.CancelledError):
        material.build(tmp_path / "a.bsdf", nodes=40, orders=20, cancel=flag)

    def stop(fraction, stage):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        material.build(tmp_path / "b.bsdf", nodes=40, orders=20, progress=stop)
    assert list(tmp_path.iterdir()) == []


def test_cancel_from_another_thread(tmp_path):
    material = ll.Material.parse(PLASTIC)
    flag = ll.CancelFlag()
    started = threading.Event()

    def progress(fraction, stage):
        started.set()

    def cancel_soon():
        started.wait(30)
        flag.set()

    canceller = threading.Thread(target=cancel_soon)
    canceller.start()
    try:
        material.build(tmp_path / "c.bsdf", nodes=200, orders=200, progress=progress,
                       cancel=flag)
    except ll.CancelledError:
        assert not (tmp_path / "c.bsdf").exists()
    else:  # finished before the flag was seen: the file must be whole
        assert ll.BSDFStorage(tmp_path / "c.bsdf").nodeCount == 202
    canceller.join()


def test_material_layers_evaluate_like_any_layer():
    layers, _ = ll.Material.parse("diffuse albedo=0.25\n").build_layers(nodes=16, orders=1)
    np.testing.assert_allclose(layers[0].eval(-0.5, np.array([0.2, 0.9])), 0.25 / np.pi,
                               rtol=1e-12)


def test_swept_material_builds_one_textured_file(tmp_path):
    # Material.build handles sweeps as it is: ll_material_build writes the
    # textured file (3 x 2 bases, axis 0 the coat's alpha).
    material = ll.Material.parse("set nodes=12 orders=6\n"
                                 "dielectric name=coat eta=1.5 alpha=[0.1 0.2 0.3]\n"
                                 "conductor eta=2+3i alpha=[0.1 0.3]\n")
    assert material.estimate()["layers_built"] == 5
    storage = material.build(tmp_path / "swept.bsdf")
    assert storage.basisCount == 6
    assert '"parameters": ["coat.alpha", "1.alpha"]' in storage.metadata


def test_chosen_resolutions_are_remembered(tmp_path, monkeypatch):
    # The user's cache directory by default (LAYERLAB_CACHE_DIR first; the
    # tests point it at a scratch one), an explicit one, or none.
    monkeypatch.setenv("LAYERLAB_CACHE_DIR", str(tmp_path / "user"))
    assert ll.user_cache_dir() == str(tmp_path / "user")
    metal = ll.Material.parse("conductor eta=0.2+3i alpha=0.5\n")
    first = metal.resolution()
    assert len(list((tmp_path / "user").iterdir())) == 1
    assert metal.resolution() == first
    assert metal.resolution(cache_dir=tmp_path / "own") == first
    assert len(list((tmp_path / "own").iterdir())) == 1
    assert metal.resolution(cache_dir=None) == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["own", "user"]
