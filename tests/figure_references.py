"""The one place where each checked figure names the test that compares it with an independent reference.

Two kinds of checked figures:

- the report's ``summary.json`` (``checked``): each ``Checked(name, ...)`` of ``pixelkit/report``, keyed
  here by its name as the code writes it, every ``{...}`` of an f-string written ``*``
  (``summary.*.cg_jdep_uV_per_e``);
- ``verify``'s ``signoff.json``: every figure a ``[spec]`` can name (``pixelkit.verify.figures``), keyed
  by a glob over the figure names (``conversion_gain_*``). The report's ``signoff.*`` are these.

Each entry is a list of ``Ref``: the test (``file::function``), the kind of reference (one of
``KINDS``), ``via`` - a name the test's own source must mention (the figure's key, or the function
that computes it), so the entry cannot point at an unrelated test - and what the reference is. A ref's
``only`` (a glob) narrows it to some of the entry's concrete names (the quick report's
``summary.json`` is walked by name in test_report.py).

A test named ``..._unchanged`` or marked ``@pytest.mark.round_trip`` detects change only and is
refused as a reference. ``tests/test_figure_references.py`` walks the code and this table and draws
the map in docs/validation.md from it.
"""
from __future__ import annotations

import fnmatch
from typing import NamedTuple

#: The kinds of independent reference (docs/validation.md defines each).
KINDS = ("derivation", "SPICE circuit level", "field solver", "real data", "published table", "foundry deck")


class Ref(NamedTuple):
    test: str            # tests/<file>.py::<function>
    kind: str
    via: str             # a name the test's source mentions: the figure's key or the function computing it
    reference: str       # what it is compared with
    only: str = "*"      # the concrete names (glob) this ref covers


_MS = "tests/test_models_table.py::test_table_3_2_from_spice_charge_steps"
_VF = "tests/test_verify_figures.py::"
_EXP = "tests/test_experiment.py::"
_P4T = "tests/test_pixel4t.py::"

#: summary.json: the report's checked figures, by the name pattern of their Checked(...) call.
REPORT = {
    "summary.*.cg_jdep_uV_per_e": [Ref(_MS, "SPICE circuit level", "cg_V_per_e",
                                       "ngspice charge step on each bare PD at 2.5 V")],
    "summary.*.fwc_ke": [Ref(_MS, "SPICE circuit level", "fwc_e", "swing x C_jdep / q with SPICE's C_jdep")],
    "summary.c_a": [Ref(_MS, "published table", "c_a", "the thesis's printed PD sizes 15.1 x 13.55 / 5 x 5 um")],
    "summary.c_c": [Ref(_MS, "SPICE circuit level", "c_c", "the ratio of the two SPICE charge steps")],
    "summary.*.cg_out_0_30_uV_per_e": [Ref("tests/test_report.py::test_report_output_cg_pair_against_the_analytic_level",
                                           "derivation", "cg_out_0_30_uV_per_e",
                                           "the analytic CG_out(0) = A_sf q / C (0 - 3 % above the SPICE slope)")],
    "summary.*.cg_out_0_uV_per_e": [Ref("tests/test_noise.py::test_output_cg_vs_spice_charge_step",
                                        "SPICE circuit level", "output_cg",
                                        "a SPICE charge step double-sampled at the column (5 %)")],
    "model_vs_spice.*": [
        Ref(_EXP + "test_spice_at_the_reported_currents_lands_on_the_targets", "SPICE circuit level", "i_mid_A",
            "SPICE runs at the reported currents land on 0.5 / 0.05 of swing", only="model_vs_spice.*.i_*"),
        Ref(_EXP + "test_spice_at_the_reported_currents_lands_on_the_targets", "SPICE circuit level", "swing",
            "a run at the sweep's top current, read at the sample instants", only="model_vs_spice.*.swing_V"),
        Ref(_EXP + "test_pedestal_is_the_fd_step_through_the_follower", "SPICE circuit level", "pedestal_V",
            "FD's step between the samples times the follower's operating-point gain (1 %)",
            only="model_vs_spice.*.pedestal_V"),
        Ref(_EXP + "test_target_currents_against_the_charge_chain_derivation", "derivation", "i_mid_A",
            "the analytic charge chain (transfer, TG turn-off, RS turn-on) to the targets",
            only="model_vs_spice.ratio"),
        Ref(_EXP + "test_analytic_model_vs_spice_within_5_percent", "derivation", "model_vs_spice",
            "the analytic C(V) discharge against SPICE's V(pd)", only="model_vs_spice.model_vs_spice.max_err_frac"),
        Ref(_EXP + "test_fig_a1_pds_discharge_together", "derivation", "fig_a1",
            "currents in the ratio C_C discharge both PDs alike (fig. A.1)", only="model_vs_spice.fig_a1.*"),
    ],
    "noise.read_e_*": [Ref("tests/test_noise.py::test_read_noise_chain_vs_spice_noise", "SPICE circuit level",
                           "chain", "ngspice .noise of the read chain")],
    "noise.cg_out_*": [Ref("tests/test_noise.py::test_output_cg_vs_spice_charge_step", "SPICE circuit level",
                           "output_cg", "the analytic CG_out (the other level) within 5 %")],
    "afe.gain_error_frac": [Ref("tests/test_report_sections.py::test_afe_gain_error_is_the_finite_gain_closed_form",
                                "derivation", "gain_error", "-eps / (1 + eps) of a finite-gain op-amp")],
    "afe.offset_V": [Ref("tests/test_afe.py::test_residual_is_the_finite_gain_error", "derivation", "offset",
                         "what the finite-gain model leaves is one constant offset below 30 mV")],
    "array.*.r*c*.signal_V": [Ref("tests/test_array.py::test_array_command_against_single_pixel_spice",
                                  "SPICE circuit level", "signal", "each pixel against the single-pixel bench")],
    "array.worst_split_vs_whole_mV": [Ref("tests/test_frame.py::test_row_split_matches_undivided",
                                          "SPICE circuit level", "split", "the undivided deck against the split")],
    "array.settling_worst_mV": [Ref("tests/test_settling.py::test_reference_from_where_the_reads_part_is_the_whole_long_read",
                                    "SPICE circuit level", "settling",
                                    "the long read from where the reads part equals the whole long read")],
    "*.of_full_well": [Ref("tests/test_overexposure.py::test_bright_source_figures", "derivation", "of_full_well_signal",
                           "anti-blooming keeps the pixel at the top; FD's extra charge is its own light I / gse")],
    "*.recovery_mV": [Ref("tests/test_overexposure.py::test_bright_source_figures", "derivation", "recovery_V",
                          "the next row's column within 0.5 mV of a row after a dark one")],
    "camera.*_*": [
        Ref("tests/test_camera.py::test_camera_cli_figures_against_spice", "SPICE circuit level", "k_dn_per_e",
            "K by EMVA's definition on the SPICE transfer", only="camera.k_dn_per_e_*"),
        Ref("tests/test_camera.py::test_camera_cli_figures_against_spice", "SPICE circuit level", "read_noise_e",
            "sigma_d from ngspice .noise", only="camera.sigma_d_e_*"),
        Ref("tests/test_camera.py::test_camera_cli_figures_against_spice", "derivation", "dr_db",
            "EMVA 1288: DR = mu_p.sat / mu_p.min, mu_p.min = (sigma_d + 1/2) / eta", only="camera.dr_db_*"),
    ],
    "frame.dv_kmh": [Ref("tests/test_sensor_speed.py::test_thesis_test_point_reproduces_printed_budget",
                         "published table", "budget", "[Thesis2019]'s printed error budget at its test point")],
    "frame.lowgse_best_ratio": [Ref("tests/test_sensor_lowgse.py::test_image_balance_peaks_at_the_rule", "derivation",
                                    "best_ratio", "eq. 2.16 - 2.18: equal weight of exposure and wait")],
    "frame.car_speed_60_kmh": [Ref("tests/test_sensor_double_exposure.py::test_speed_from_secondary_image_within_error_budget",
                                   "derivation", "speed", "the scene's true speed within the error budget")],
    "gap.gap_*_rms_V": [Ref("tests/test_report_sections.py::test_gap_section_names_the_true_effect_of_a_silicon_case",
                            "SPICE circuit level", "gap", "a SPICE-made silicon case with a known effect")],
    "layout.c_a": [Ref("tests/test_report_sections.py::test_layout_c_a_is_the_thesis_ratio", "published table", "c_a",
                       "[Thesis2019]'s 15.1 x 13.55 / 5 x 5 um")],
    "layout.*.pd_area_m2": [Ref("tests/test_layout.py::test_extracted_geometry_equals_drawn", "derivation", "area",
                                "KLayout's extraction against the geometry written in the test")],
    "layout.*.photoactive_area_m2": [Ref("tests/test_layout.py::test_extracted_geometry_equals_drawn", "derivation",
                                         "photoactive", "KLayout's extraction against the geometry written in the test")],
    "layout_signoff.drc_violations": [Ref("tests/test_layout.py::test_foundry_deck_finds_no_violation_in_any_generated_cell",
                                          "foundry deck", "drc", "the GF180MCU DRC deck on every generated cell")],
    "layout_signoff.lvs_match": [Ref("tests/test_layout.py::test_lvs_catches_an_open", "derivation", "lvs",
                                     "broken layouts written in the test are caught (open, short, swapped nets, W / L)")],
    "layout_signoff.open_*": [Ref("tests/test_lightmap.py::test_exposed_area_against_the_gds", "derivation", "exposed",
                                  "gdstk booleans on the written GDS, no netlist")],
    "light_map.readout_area_pixels_m2": [Ref("tests/test_lightmap.py::test_exposed_area_against_the_gds", "derivation",
                                             "exposed", "gdstk booleans on the written GDS, no netlist")],
    "light_map.worst_error_over_noise_pixels": [
        Ref("tests/test_lightmap.py::test_light_map_error_within_the_charge_bound_and_a_full_shield_cures_it",
            "derivation", "_charge_bound",
            "J A t / C: the charge the SC AFE's island collects after its reset, on C13 (ideal charge analysis), "
            "plus the 50 uV resolution of a SPICE difference; the DC-operating-point figure breaks it")],
    "post_layout.cg_model_vs_spice_frac": [
        Ref("tests/test_post_layout.py::test_conversion_gain_model_vs_spice_within_2_percent_post_layout",
            "SPICE circuit level", "output_cg", "a SPICE charge step on the post-layout netlist")],
    "post_layout.c_fd_*_F": [Ref("tests/test_extraction.py::test_fd_node_within_15_percent_of_fastcap", "field solver",
                                 "fastcap", "FastCap2 on the same stack")],
    "schematics.*.elements": [Ref("tests/test_report.py::test_schematics_draw_every_element_of_the_golden_netlists",
                                  "derivation", "elements", "the golden decks parsed as text")],
    "sizing.c_m": [Ref("tests/test_sizing.py::test_spice_level_is_the_closed_form_of_the_experiments_currents",
                       "derivation", "c_m", "C_M = 12 (A_s / A_p)(i_mid / i_5pct)")],
    "sizing.mask_open_m2": [Ref("tests/test_sizing.py::test_analytic_level_matches_its_closed_form", "derivation",
                                "mask_open_m2", "Q_low / (j t_ratio t_p), charges from the integral of C(V)")],
    "sizing.t_int_*_s": [Ref("tests/test_sizing.py::test_spice_level_is_the_closed_form_of_the_experiments_currents",
                             "derivation", "t_int_primary_s", "t_p = i_mid t_w / (j A_p), t_s = t_ratio t_p")],
    "sizing.verify.*_frac": [Ref("tests/test_sizing.py::test_verify_in_spice", "SPICE circuit level", "primary_frac",
                                 "a SPICE run at the sized real integration times (0.5005 / 0.0507)")],
    "variation.secondary_pedestal_V": [
        Ref("tests/test_montecarlo.py::test_dsnu_prnu_column_fpn_and_pedestal_against_linear_propagation",
            "derivation", "pedestal", "linear propagation of the model card's sigmas")],
    "variation.offset_fpn_ratio": [Ref("tests/test_montecarlo.py::test_offset_fpn_matches_pelgrom", "derivation",
                                       "pelgrom", "Pelgrom: G_SF sigma_VT")],
    "light.effective_opening_m2": [Ref("tests/test_light_model.py::test_a_modelled_design_uses_the_model", "derivation",
                                       "photoactive_area", "A_primary x R_secondary / R_primary recomputed from the "
                                       "model's eta (its physics: tests/test_light_physics.py's closed forms)")],
    "light.gse_*": [Ref("tests/test_light_model.py::test_gse_within_the_published_range_of_fd_storage_pixels",
                        "published table", "gse", "Aptina's FD-storage global shutters, GSE 310 - 3000 "
                        "([Thesis2019]'s table)")],
    "signoff.*": [],      # each spec's figure: SIGNOFF below
    "pixel.*": [   # a pixel read by role (report.sections.pixel): the 4T's figures against their closed forms
        Ref(_P4T + "test_full_well_conversion_gain_dark_current_against_their_derivations", "derivation",
            "conversion_gain_model_uV_per_e", "A_sf q / C_FD (families/pixel4t/model.py), 5 %",
            only="pixel.conversion_gain_uV_per_e"),
        Ref(_P4T + "test_full_well_conversion_gain_dark_current_against_their_derivations", "derivation",
            "dark_current_model_e_per_s", "I_gen + I_dif of physics/ppd.py, 5 %", only="pixel.dark_current_e_per_s"),
        Ref(_P4T + "test_full_well_conversion_gain_dark_current_against_their_derivations", "derivation",
            "power_estimate_W", "the loads' bias x supply x (1 + duty), 5 %", only="pixel.power_chip_W"),
        Ref(_P4T + "test_full_well_conversion_gain_dark_current_against_their_derivations", "derivation",
            "dark_model_e", "between the PPD's dark (C_PPD V_pin) and bright-light full wells",
            only="pixel.full_well_e"),
        Ref(_P4T + "test_full_well_conversion_gain_dark_current_against_their_derivations", "derivation",
            "ppd_full_well", "the overflow balance I_dif (exp(-V_F/U_T) - 1) = I_ph + I_gen, 0.5 %",
            only="pixel.ppd_full_well_e"),
        Ref(_P4T + "test_lag_at_the_output_with_a_barrier", "derivation", "lag_run",
            "Ppd.residual over the read's and the next shutter's transfers (8 %)", only="pixel.image_lag_*"),
        Ref(_P4T + "test_transient_noise_agrees_with_the_noise_analysis", "SPICE circuit level", "read_noise",
            "the read in the time domain with each device's noise as TRNOISE sources", only="pixel.read_noise_e"),
    ],
}

#: signoff.json: verify's figures (pixelkit.verify.figures), by a glob over their names.
SIGNOFF = {
    "conversion_gain_*": [Ref(_VF + "test_conversion_gains_against_the_analytic_level", "derivation",
                              "conversion_gain", "the analytic CG_out of PD node + FD times A_sf (5 %)")],
    "pd_conversion_gain_*": [Ref(_VF + "test_conversion_gains_against_the_analytic_level", "derivation",
                                 "pd_conversion_gain", "q / C(V) of the PD node with its switches (2 %)")],
    "swing_*": [Ref(_VF + "test_swing_full_well_and_dynamic_range_against_the_experiment", "SPICE circuit level",
                    "swing", "the thesis experiment's own swing (1 %)")],
    "full_well_*": [Ref(_VF + "test_swing_full_well_and_dynamic_range_against_the_experiment", "derivation",
                        "full_well", "the experiment's swing over the analytic CG (6 %)")],
    "dynamic_range_*": [Ref(_VF + "test_swing_full_well_and_dynamic_range_against_the_experiment", "derivation",
                            "dynamic_range", "that full well over the read noise (0.6 dB)")],
    "read_noise_*": [Ref("tests/test_noise.py::test_read_noise_chain_vs_spice_noise", "SPICE circuit level", "chain",
                         "ngspice .noise of the read chain"),
                     Ref("tests/test_afe_noise.py::test_afe_noise_vs_spice", "SPICE circuit level", "afe",
                         "ngspice .noise of the AFE")],
    "ktc_noise_*": [Ref(_VF + "test_ktc_noise_against_spice_noise_of_the_reset_sample", "SPICE circuit level",
                        "ktc_noise", "ngspice .noise of FD as RST leaves it (5 %)")],
    "pd_dark_drop_*": [Ref(_VF + "test_dark_drop_against_the_analytic_discharge", "derivation", "pd_dark_drop",
                           "the C(V) discharge by the dark current and the switch leakage (10 %)")],
    "image_lag_*": [Ref(_VF + "test_image_lag_of_a_hard_reset_and_afe_gain_error", "derivation", "image_lag",
                        "a hard reset leaves no lag"),
                    Ref("tests/test_circuit_choices.py::test_boosted_gates_keep_the_reset_hard_at_a_low_supply",
                        "derivation", "image_lag", "a gate a threshold below the reset level resets softly (lag %)")],
    "gse_*": [Ref(_VF + "test_gse_against_the_analytic_storage_signal", "derivation", "gse",
                  "A_sf (I / gse + leakage) t / C_FD where FD stores (12 %)")],
    "storage_light_*": [Ref("tests/test_light_model.py::test_storage_light_is_the_fd_charge_through_the_readout",
                            "derivation", "storage", "A_sf I_FD t / C_FD where it does not clip (10 %); the swing "
                            "where it does")],
    "settling_*": [Ref("tests/test_settling.py::test_reference_from_where_the_reads_part_is_the_whole_long_read",
                       "SPICE circuit level", "settling", "the converged long read")],
    "criterion_secondary": [Ref(_VF + "test_criterion_against_the_experiments_secondary_transfer",
                                "SPICE circuit level", "criterion_secondary",
                                "the experiment's secondary transfer at the equivalent current (0.3 % of swing)")],
    "afe_gain_error": [Ref(_VF + "test_image_lag_of_a_hard_reset_and_afe_gain_error", "derivation", "afe_gain_error",
                           "eps / (1 + eps) of the finite-gain charge balance (10 %)")],
    "power_*": [Ref("tests/test_verify.py::test_power_scales_with_supply_and_matches_bias_currents", "derivation",
                    "power", "bias currents x supply x duty, the OTA's mirror ratios")],
}


def uncovered_names(names, report: dict | None = None) -> list:
    """Concrete ``summary.json`` names no entry covers (the ``signoff.<spec>`` ones are the
    verify figures', walked by tests/test_figure_references.py)."""
    report = REPORT if report is None else report
    out = []
    for n in names:
        if n.startswith("signoff."):
            continue
        # summary.json writes a code's ``*_frac`` figure as ``*_pct`` in % (report.build.as_percent)
        code = {n, n[:-4] + "_frac"} if n.endswith("_pct") else {n}
        if not any(fnmatch.fnmatchcase(c, r.only) for c in code
                   for k, rs in report.items() if fnmatch.fnmatchcase(c, k) for r in rs):
            out.append(n)
    return out
