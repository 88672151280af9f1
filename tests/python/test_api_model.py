"""legsim.Model: a model file loaded at run time by the library's own loader is the
compiled-in model, bit for bit; a changed file changes the physics as it should; a
broken file raises ModelError with the loader's message."""
from __future__ import annotations

import ctypes as C

import numpy as np
import pytest

import legsim

G = 9.81  # models/leg.toml: gravity = [0, -9.81] m/s^2


def test_the_library_reports_its_build_and_matches_config_h(root):
    lib = legsim.load_library("double")
    assert lib.config_source == "legsim_build_info"
    # the facts are those of the build's generated header (one source of truth) when the
    # header sits next to the library (a build tree)
    headers = [p for p in (lib.path.parent / "generated" / "legsim" / "config.h",)
               if p.is_file()]
    for h in headers:
        cfg = legsim._lib.parse_config_h(h)
        for k, v in cfg.items():
            assert lib.config[k] == v, k
    assert lib.config["sizeof(legsim_model_desc)"] == C.sizeof(lib.ModelDesc)
    assert lib.config["sizeof(legsim_real)"] == 8 and lib.config["LEGSIM_USE_FLOAT"] == 0


@pytest.mark.parametrize("variant", ["revolute", "slot"])
def test_model_file_equals_the_compiled_in_model(model_toml, precision, variant):
    f = legsim.Model.from_toml(model_toml, variant, precision=precision)
    b = legsim.Model.builtin(variant, precision=precision)
    assert bytes(f.desc) == bytes(b.desc)
    assert f.name == "inta-csic-leg" and f.variant == variant
    assert f.body_names == ["upper_cylinder", "upper_rod", "thigh", "lower_cylinder",
                            "lower_rod", "shank"]
    np.testing.assert_array_equal(f.masses, [1.2, 0.4, 1.5, 1.0, 0.3, 1.8])
    np.testing.assert_array_equal(f.strokes, [[0.40, 0.80], [0.35, 0.70]])
    assert f.actuator_names == ["upper", "lower"] and f.pose_names == ["stand"]
    f.check()


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_sim_from_the_file_runs_bit_identical_to_the_compiled_in_leg(model_toml, precision,
                                                                    stand, integrator):
    def run(model):
        s = stand(model, precision=precision, integrator=integrator, step=1e-3)
        F = s.statics()
        s.command_force("upper", 60.0)
        s.command_length("lower", 0.60)
        s.set_force("foot_load", [10.0, 200.0])
        s.step(300)
        return F.tobytes() + s.state_bytes() + s.reactions().tobytes()
    assert run(str(model_toml)) == run(None)


def test_model_variants(model_toml):
    assert legsim.model_variants(model_toml) == ["revolute", "slot"]
    assert legsim.builtin_variants() == ["revolute", "slot"]
    with pytest.raises(legsim.BadInputError) as e:
        legsim.Model.from_toml(model_toml, "telescopic")
    assert e.value.status_name == "LEGSIM_ERR_BAD_INPUT" and "telescopic" in e.value.text
    with pytest.raises(legsim.BadInputError):
        legsim.Model.builtin("telescopic")


def _dy_shank_dl(s: legsim.Sim, eps=1e-6) -> np.ndarray:
    """d(y of the shank's centre)/d(actuator lengths) by central differences of assembly."""
    l0, _ = s.actuator_lengths()
    q0 = s.q
    out = []
    for k in range(s.n_actuators):
        ys = []
        for sgn in (1, -1):
            s.set_state(q0)
            s.assemble(l0 + sgn * eps * np.eye(s.n_actuators)[k])
            ys.append(s.q[3 * 5 + 1])
        out.append((ys[0] - ys[1]) / (2 * eps))
    s.set_state(q0)
    s.assemble(l0)
    return np.array(out)


def test_a_heavier_shank_changes_statics_as_virtual_work_says(model_toml, stand, tmp_path):
    dm = 2.5  # kg more on the shank (body 6, mass 1.80)
    text = model_toml.read_text()
    old = 'name = "shank"\nlength = 0.60\nmass = 1.80'
    assert old in text
    heavy = tmp_path / "heavy_leg.toml"
    heavy.write_text(text.replace(old, f'name = "shank"\nlength = 0.60\nmass = {1.80 + dm}'))
    base, hv = stand(str(model_toml)), stand(str(heavy))
    assert hv.model.masses[5] == pytest.approx(1.80 + dm, abs=1e-15)
    np.testing.assert_array_equal(hv.q, base.q)  # the pose is geometry only
    dF = hv.statics() - base.statics()
    frame = [0, 2, 3]  # joints A, B_thigh, B_lower (revolute_to_frame)
    dR = hv.reactions()[frame, :2].sum(axis=0) - base.reactions()[frame, :2].sum(axis=0)
    # actuator forces do the work that lifts the extra weight: dF . dl = dm g dy
    np.testing.assert_allclose(dF, dm * G * _dy_shank_dl(base), rtol=1e-6, atol=1e-6)
    assert np.max(np.abs(dF)) > 10.0  # a real change, not round-off
    # and the frame carries the extra weight
    np.testing.assert_allclose(dR, [0.0, dm * G], atol=1e-9)


def test_model_from_a_string_and_its_messages(model_toml):
    text = model_toml.read_text()
    m = legsim.Model.from_toml_string(text, source_name="leg-copy.toml")
    assert bytes(m.desc) == bytes(legsim.Model.builtin().desc)
    broken = text.replace('bodies = [5, 6]\nends = ["distal", "at"]',
                          'bodies = [5, 7]\nends = ["distal", "at"]')
    assert broken != text
    with pytest.raises(legsim.ModelError) as e:
        legsim.Model.from_toml_string(broken, source_name="leg-copy.toml")
    assert e.value.status_name == "LEGSIM_ERR_MODEL"
    assert e.value.text == "leg-copy.toml: joint 'D': body 7 does not exist (ids are 1..6)"
    with pytest.raises(legsim.ModelError) as e:
        legsim.Model.from_toml_string("name = [", source_name="bad.toml")
    assert e.value.text.startswith("bad.toml")


def test_a_missing_model_file_says_which(tmp_path):
    with pytest.raises(legsim.LegsimError) as e:
        legsim.Sim(tmp_path / "nope.toml")
    assert e.value.status_name == "LEGSIM_ERR_BAD_INPUT" and "nope.toml" in e.value.text


def test_a_model_moves_between_precisions(model_toml, stand):
    if not legsim.library_available("float"):
        pytest.skip("liblegsim_f32.so is not built")
    m = legsim.Model.from_toml(model_toml)  # double library
    s = stand(m, precision="float")
    assert s.precision == "float" and s.library.real is C.c_float
    assert bytes(s.model.desc) == bytes(m.desc)
