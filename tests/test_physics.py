import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pixelkit.constants import C0, H, K_B, Q
from pixelkit.physics import discharge, noise, photo
from pixelkit.physics.dark import dark_current
from pixelkit.physics.junction import Junction, Node, capacitance, charge
from pixelkit.physics.saturation import saturation_times
from pixelkit.physics.subpixel import pd_node


def test_charge_is_the_integral_of_capacitance(ref_design):
    j = Junction.of(ref_design.tech.photodiode)
    v = np.linspace(0, 3, 3001)
    c = capacitance(v, 25e-12, 20e-6, j)
    q_num = np.concatenate([[0], np.cumsum((c[1:] + c[:-1]) / 2 * np.diff(v))])
    assert charge(v, 25e-12, 20e-6, j) == pytest.approx(q_num, rel=1e-6, abs=1e-22)


def test_discharge_matches_an_ode_integration(ref_design):
    node = pd_node(ref_design, "primary", parasitics=True)
    i, v0 = 1.4e-9, 2.5
    t = np.linspace(0, 30e-6, 61)
    sol = solve_ivp(lambda _t, v: [-i / node.capacitance(v[0])], (0, t[-1]), [v0], t_eval=t,
                    rtol=1e-10, atol=1e-12)
    assert discharge.voltage(t, node, v0, i) == pytest.approx(sol.y[0], abs=1e-6)


def test_fig_3_6_saturation_time_scales_as_one_over_opening(ref_design):
    tech = ref_design.tech
    node = pd_node(ref_design, "secondary")
    openings = np.array([0.2, 0.4, 0.64, 1.0, 5.0, 25.0]) * 1e-12
    e = 1.17e-6 / 1e-12  # 1.17 uW/um2 in W/m2
    i, lin, cv = saturation_times(node, 2.5, e, photo.Spectrum.monochromatic(850e-9), tech.qe, openings)
    assert lin * openings == pytest.approx(np.full(6, lin[0] * openings[0]), rel=1e-9)
    assert cv * openings == pytest.approx(np.full(6, cv[0] * openings[0]), rel=1e-9)
    # the thesis's [Thesis2019] linear form: t = 2.5 V C_jdep / I_ph
    assert lin == pytest.approx(2.5 * node.capacitance(2.5) / i, rel=1e-12)
    # with C(V) discharge to 0 V takes longer: C at lower bias is larger. The
    # amount is the mean of C over 0..2.5 V over C(2.5 V), computed independently:
    v = np.linspace(0, 2.5, 20001)
    c_mean = np.trapezoid(node.capacitance(v), v) / 2.5
    assert cv / lin == pytest.approx(np.full(6, c_mean / node.capacitance(2.5)), rel=1e-6)
    assert cv[0] / lin[0] > 1.0


def test_responsivity_and_photometry():
    # R = eta q lambda / hc: 0.6856 A/W per unit QE at 850 nm
    assert photo.responsivity(850e-9, 1.0) == pytest.approx(Q * 850e-9 / (H * C0))
    assert photo.responsivity(850e-9, 1.0) == pytest.approx(0.6856, rel=1e-3)
    # 555 nm: 683 lm/W by the definition of the candela
    line = photo.Spectrum.monochromatic(555e-9)
    assert photo.irradiance_to_lux(1.0, line) == pytest.approx(683.0, rel=0.01)
    assert photo.lux_to_irradiance(photo.irradiance_to_lux(2.0, line), line) == pytest.approx(2.0)
    # an ideal black body at 7000 K radiates about 95 lm/W (whole spectrum)
    bb = photo.Spectrum.blackbody(7000.0, lo=100e-9, hi=100e-6, n=400000)
    assert photo.luminous_efficacy(bb) == pytest.approx(95.0, rel=0.03)


def test_photocurrent_of_a_line_is_r_e_a(ref_design):
    qe = ref_design.tech.qe
    i = photo.photocurrent(100.0, 1e-10, photo.Spectrum.monochromatic(850e-9), qe)
    assert i == pytest.approx(photo.responsivity(850e-9, qe(850e-9)) * 100.0 * 1e-10)


def test_dark_current_law_against_spice_and_two_geometries(ref_design):
    """Independent path: ngspice's reverse current of the PD card at 2.5 V for both PD geometries
    (204.6 um2 / 57.3 um and 25 um2 / 20 um). As the source's method has it (fit J_A and J_P from the
    two geometries, I = (J_A A + J_P P) 2^((T - T_ref) / T_d)): the 2 x 2 solve of the SPICE currents
    gives the technology's area and perimeter densities (0.1 %), SPICE's current at T_ref + T_d is
    twice that at T_ref, and ``dark_current`` equals SPICE's at every geometry and temperature."""
    from conftest import pd_reverse_currents
    pd, p, s = ref_design.tech.photodiode, ref_design.primary, ref_design.secondary
    geo = [(p.area, p.perimeter), (s.area, s.perimeter)]
    temps = (pd.t_ref, pd.t_ref + pd.dark_doubling)
    i = pd_reverse_currents(ref_design, geo, temps)
    j_a, j_p = np.linalg.solve(np.array(geo), [i[(*g, pd.t_ref)] for g in geo])
    assert j_a == pytest.approx(pd.dark_area, rel=1e-3) and j_p == pytest.approx(pd.dark_perimeter, rel=1e-3)
    for g in geo:
        assert i[(*g, temps[1])] / i[(*g, temps[0])] == pytest.approx(2.0, rel=1e-3)
        for t in temps:
            assert dark_current(*g, t, pd) == pytest.approx(i[(*g, t)], rel=1e-3)


def test_ktc_noise():
    c = 26.54e-15
    assert noise.ktc_voltage(c, 300) == pytest.approx(np.sqrt(K_B * 300 / c))
    # sqrt(kT/C) at 26.54 fF, 300 K: about 395 uV and 65 e- for the primary
    assert noise.ktc_voltage(c, 300) == pytest.approx(395e-6, rel=0.01)
    assert noise.ktc_electrons(c, 300) == pytest.approx(65, rel=0.02)
    assert noise.shot_electrons(10000) == pytest.approx(100)


def test_node_inversion_round_trips(ref_design):
    node = Node(((25e-12, 20e-6, Junction.of(ref_design.tech.photodiode)),), 1e-15)
    v = np.linspace(-0.3, 3.3, 50)
    assert node.bias_for_charge(node.charge(v)) == pytest.approx(v, abs=1e-9)
