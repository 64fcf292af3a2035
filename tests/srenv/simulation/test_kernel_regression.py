"""Regression of the kernel refactor (issue 15): trajectories identical to the pre-refactor kernel.

REFERENCE was computed with the kernel of commit cb22ba4 (before the laws moved into srenv/laws and the
kernel took its named calling convention) by the very functions below. Every path is covered: Coulomb
and survey side force (fig4), vertical (fig3), nonmonotone valve law and DC iterations (fig6), fluid
pound with inflow (default at 9 SPM, the last stroke pounds), gas interference (gas spring inside the DC
loop), unanchored tubing (tubing spring), the ProxSuite fallback at every pattern change (max_corrections
0), a pull-out, run_velocity with its start state and the Hopf spring-block (the kernel's second caller).
Floats must agree to 1e-10 relative (in practice they are bit-for-bit), counts exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from srenv.config import load_config
from srenv.simulation.hopf import SpringBlock
from srenv.simulation.simulator import Simulator

CASES = {
    "fig3": ("paper_fig3_vertical", [], 2),
    "fig4": ("paper_fig4_deviated", [], 2),
    "fig6": ("paper_fig6_nonmonotone", [], 2),
    "default_pound": ("default", ["inflow.max_rate_m3_day=8", "inflow.initial_fluid_level_m=1", "surface.spm=9"], 5),
    "gas": ("default", ["inflow.model=none", "pump.intake_gas_fraction=0.2"], 3),
    "tubing": ("paper_fig3_vertical", ["tubing.anchored=false"], 2),
    "fig4_qp": ("paper_fig4_deviated", ["simulation.max_corrections=0"], 1),
    "pullout": ("paper_fig7_pullout", [], 0),
}


def figures(key):
    name, over, n = CASES[key]
    sim = Simulator(load_config(name, over))
    runs = [sim.run_duration(4.0)] if n == 0 else sim.run_strokes(n)
    out = {}
    for i, r in enumerate(runs):
        tr = r.trace
        load = tr["polished_rod_load_n"]
        out[f"{i}_pprl"] = float(load.max())
        out[f"{i}_mprl"] = float(load.min())
        out[f"{i}_pump_stroke"] = float(np.ptp(tr["pump_position_m"]))
        out[f"{i}_fillage"] = float(r.fillage)
        out[f"{i}_load_sum"] = float(np.sum(load))
        out[f"{i}_pump_load_sum"] = float(np.sum(tr["pump_load_n"]))
        out[f"{i}_pump_pos_sum"] = float(np.sum(tr["pump_position_m"]))
        out[f"{i}_pump_vel_abs"] = float(np.sum(np.abs(tr["pump_velocity_m_s"])))
        out[f"{i}_emax_sum"] = float(np.sum(r.element_force_max_eq_n))
        out[f"{i}_pumped"] = float(r.pumped_m3)
        out[f"{i}_work"] = float(r.energy_j["polished_rod_work_j"])
        out[f"{i}_counts"] = (
            r.certified_steps,
            r.corrected_steps,
            r.qp_steps,
            r.qp_calls,
            r.dc_iterations,
            int(np.sum(r.rod_stick_episodes)),
            len(r.events),
        )
    return out


def hopf_figures():
    blk = SpringBlock(1.0, 100.0, 0.5, 10.0, 6.0, 0.2)
    t, v = blk.simulate(0.3, 5.0, 0.01, 1e-4)
    return {"v_sum": float(np.sum(v)), "v_last": float(v[-1]), "n": len(t)}


def velocity_figures():
    sim = Simulator(load_config("paper_fig4_deviated"))
    t = np.arange(1, 801) * 0.01
    va = 0.8 * np.sin(2 * np.pi * t / 8.0)
    r = sim.run_velocity(va, 0.01, start_velocity_m_s=0.0, start_acceleration_m_s2=0.8 * 2 * np.pi / 8.0)
    return {
        "load_sum": float(np.sum(r.trace["polished_rod_load_n"])),
        "pprl": float(r.trace["polished_rod_load_n"].max()),
        "counts": (r.certified_steps, r.corrected_steps, r.qp_steps),
    }


# computed at cb22ba4 (pre-refactor) by /tmp generator running the functions above
REFERENCE = {
    "default_pound": {
        "0_counts": (1259, 75, 0, 0, 1334, 65, 1),
        "0_emax_sum": 1214623.9419940065,
        "0_fillage": 1.0,
        "0_load_sum": 42748694.33472936,
        "0_mprl": 15577.699112387449,
        "0_pprl": 49855.413753935296,
        "0_pump_load_sum": 4668770.51648889,
        "0_pump_pos_sum": 784.043588623893,
        "0_pump_stroke": 1.4724399550346112,
        "0_pump_vel_abs": 583.4966546998822,
        "0_pumped": 0.002240143630493409,
        "0_work": 26424.186511580465,
        "1_counts": (1273, 61, 0, 0, 1334, 36, 2),
        "1_emax_sum": 1226954.2537218255,
        "1_fillage": 1.0,
        "1_load_sum": 43018325.306852415,
        "1_mprl": 15691.634801628945,
        "1_pprl": 49329.94924115298,
        "1_pump_load_sum": 4952244.435123134,
        "1_pump_pos_sum": 780.3944925267721,
        "1_pump_stroke": 1.4760111007551724,
        "1_pump_vel_abs": 590.5564226355834,
        "1_pumped": 0.00228935102666622,
        "1_work": 53301.42794666768,
        "2_counts": (1267, 67, 0, 0, 1334, 43, 2),
        "2_emax_sum": 1223266.9919678222,
        "2_fillage": 1.0,
        "2_load_sum": 43037714.28409554,
        "2_mprl": 15739.279684925756,
        "2_pprl": 49196.9424840323,
        "2_pump_load_sum": 4972969.415694911,
        "2_pump_pos_sum": 780.104918065143,
        "2_pump_stroke": 1.4746275688942652,
        "2_pump_vel_abs": 590.1095569853674,
        "2_pumped": 0.002288032500667665,
        "2_work": 80164.68466280885,
        "3_counts": (1258, 76, 0, 0, 1334, 38, 2),
        "3_emax_sum": 1224988.4083802921,
        "3_fillage": 1.0,
        "3_load_sum": 43041187.92253256,
        "3_mprl": 15730.275316352509,
        "3_pprl": 49256.46499428793,
        "3_pump_load_sum": 4974497.224166048,
        "3_pump_pos_sum": 780.0704221507258,
        "3_pump_stroke": 1.4748260727980047,
        "3_pump_vel_abs": 590.2138176475603,
        "3_pumped": 0.0022885330138190264,
        "3_work": 107038.54184082648,
        "4_counts": (1189, 145, 0, 0, 1334, 33, 2),
        "4_emax_sum": 1224901.414285038,
        "4_fillage": 0.6698490679590386,
        "4_load_sum": 45224321.96523436,
        "4_mprl": 13106.918569063664,
        "4_pprl": 49247.330819331415,
        "4_pump_load_sum": 7285835.837151131,
        "4_pump_pos_sum": 749.9973285125899,
        "4_pump_stroke": 1.4826363898736288,
        "4_pump_vel_abs": 591.7778853341229,
        "4_pumped": 0.0015329612677609254,
        "4_work": 128367.7215902707,
    },
    "fig3": {
        "0_counts": (1993, 7, 0, 0, 2000, 0, 1),
        "0_emax_sum": 1152277.7600707214,
        "0_fillage": 1.0,
        "0_load_sum": 61549823.99027914,
        "0_mprl": 18492.119864708973,
        "0_pprl": 43354.69129937924,
        "0_pump_load_sum": 7203996.236411395,
        "0_pump_pos_sum": 1866.6076542751548,
        "0_pump_stroke": 2.223039053580764,
        "0_pump_vel_abs": 888.8945620212971,
        "0_pumped": 0.0034496934514990384,
        "0_work": 29076.81979303894,
        "1_counts": (1992, 8, 0, 0, 2000, 0, 2),
        "1_emax_sum": 1150937.782724635,
        "1_fillage": 1.0,
        "1_load_sum": 61664261.589952275,
        "1_mprl": 18380.089118510736,
        "1_pprl": 43317.99063246486,
        "1_pump_load_sum": 7298043.261612734,
        "1_pump_pos_sum": 1864.937507077777,
        "1_pump_stroke": 2.231816937896068,
        "1_pump_vel_abs": 892.8349259994542,
        "1_pumped": 0.0034633148991257664,
        "1_work": 58251.07609281611,
    },
    "fig4": {
        "0_counts": (1900, 100, 0, 0, 2000, 120, 1),
        "0_emax_sum": 1180268.2455078145,
        "0_fillage": 1.0,
        "0_load_sum": 64592533.0440058,
        "0_mprl": 18281.384632354744,
        "0_pprl": 47195.99319306951,
        "0_pump_load_sum": 7504472.504964953,
        "0_pump_pos_sum": 1168.7959368790252,
        "0_pump_stroke": 1.4205269317553033,
        "0_pump_vel_abs": 565.8832012109121,
        "0_pumped": 0.0021861882361414856,
        "0_work": 26593.209805849514,
        "1_counts": (1912, 88, 0, 0, 2000, 103, 2),
        "1_emax_sum": 1179986.954412286,
        "1_fillage": 1.0,
        "1_load_sum": 64775949.41517017,
        "1_mprl": 18291.87884923448,
        "1_pprl": 47122.903565802815,
        "1_pump_load_sum": 7658604.25051286,
        "1_pump_pos_sum": 1166.566673043248,
        "1_pump_stroke": 1.423539083265735,
        "1_pump_vel_abs": 569.4338999288157,
        "1_pumped": 0.0022090360696024273,
        "1_work": 53421.80066597152,
    },
    "fig4_qp": {
        "0_counts": (1900, 0, 100, 100, 2000, 120, 1),
        "0_emax_sum": 1180268.2455078145,
        "0_fillage": 1.0,
        "0_load_sum": 64592533.044005804,
        "0_mprl": 18281.384632359397,
        "0_pprl": 47195.99319306904,
        "0_pump_load_sum": 7504472.504964599,
        "0_pump_pos_sum": 1168.7959368790277,
        "0_pump_stroke": 1.4205269317553186,
        "0_pump_vel_abs": 565.8832012109174,
        "0_pumped": 0.002186188236141502,
        "0_work": 26593.20980584971,
    },
    "fig6": {
        "0_counts": (1665, 335, 0, 0, 9222, 201, 1),
        "0_emax_sum": 1295532.0516489004,
        "0_fillage": 1.0,
        "0_load_sum": 62754369.53945671,
        "0_mprl": 18470.7076597135,
        "0_pprl": 49807.45734032336,
        "0_pump_load_sum": 5901802.360488449,
        "0_pump_pos_sum": 1191.3398031323227,
        "0_pump_stroke": 1.4355187464837735,
        "0_pump_vel_abs": 571.718557067174,
        "0_pumped": 0.0022083144175622555,
        "0_work": 23978.026134843505,
        "1_counts": (1683, 317, 0, 0, 9378, 169, 2),
        "1_emax_sum": 1293752.904533603,
        "1_fillage": 1.0,
        "1_load_sum": 63056563.86804141,
        "1_mprl": 18371.313177932298,
        "1_pprl": 49590.4313599724,
        "1_pump_load_sum": 6194801.629287245,
        "1_pump_pos_sum": 1187.3926559154856,
        "1_pump_stroke": 1.4303886424461014,
        "1_pump_vel_abs": 572.1492464499192,
        "1_pumped": 0.0022196169711454898,
        "1_work": 48033.58076236613,
    },
    "gas": {
        "0_counts": (1901, 99, 0, 0, 4507, 120, 1),
        "0_emax_sum": 1068324.3542599166,
        "0_fillage": 0.7905134509953833,
        "0_load_sum": 64468348.49775234,
        "0_mprl": 18773.127519443875,
        "0_pprl": 43048.77213367018,
        "0_pump_load_sum": 7563772.977951562,
        "0_pump_pos_sum": 1168.884856878358,
        "0_pump_stroke": 1.4559493259286485,
        "0_pump_vel_abs": 579.2057253546607,
        "0_pumped": 0.0017665628130559357,
        "0_work": 21262.03127861829,
        "1_counts": (1906, 94, 0, 0, 4018, 124, 2),
        "1_emax_sum": 1094272.519748559,
        "1_fillage": 0.7906491387836374,
        "1_load_sum": 64707326.874406524,
        "1_mprl": 18568.53481725835,
        "1_pprl": 44694.04718124558,
        "1_pump_load_sum": 7798230.722367201,
        "1_pump_pos_sum": 1165.7616433156368,
        "1_pump_stroke": 1.4609758975025269,
        "1_pump_vel_abs": 584.3196564592693,
        "1_pumped": 0.0017925045445007946,
        "1_work": 42843.273797762005,
        "2_counts": (1913, 87, 0, 0, 4017, 119, 2),
        "2_emax_sum": 1093345.5426256396,
        "2_fillage": 0.7906446103551523,
        "2_load_sum": 64704342.23109928,
        "2_mprl": 18584.48221290804,
        "2_pprl": 44662.97420640785,
        "2_pump_load_sum": 7795346.6976754675,
        "2_pump_pos_sum": 1165.8048987551042,
        "2_pump_stroke": 1.460313333000842,
        "2_pump_vel_abs": 584.1164105192339,
        "2_pumped": 0.0017916266302809528,
        "2_work": 64415.0520061927,
    },
    "hopf": {"n": 500, "v_last": 0.0, "v_sum": 147.7358393256671},
    "pullout": {
        "0_counts": (746, 54, 0, 0, 1592, 45, 0),
        "0_emax_sum": 1009882.6847240477,
        "0_fillage": 1.0,
        "0_load_sum": 25739582.604310982,
        "0_mprl": 24573.191103378016,
        "0_pprl": 40100.69155554203,
        "0_pump_load_sum": 2120301.7961633727,
        "0_pump_pos_sum": -93.29431060598014,
        "0_pump_stroke": 0.0,
        "0_pump_vel_abs": 0.0,
        "0_pumped": 0.0,
        "0_work": 6119.423627634706,
    },
    "tubing": {
        "0_counts": (2000, 0, 0, 0, 4004, 0, 2),
        "0_emax_sum": 1136593.194747426,
        "0_fillage": 1.0,
        "0_load_sum": 61551838.37905827,
        "0_mprl": 19472.453380794617,
        "0_pprl": 42697.64468637502,
        "0_pump_load_sum": 7173319.028260505,
        "0_pump_pos_sum": 1866.833384465715,
        "0_pump_stroke": 2.235688438396953,
        "0_pump_vel_abs": 894.6200079043051,
        "0_pumped": 0.003373607444243795,
        "0_work": 28458.03266604597,
        "1_counts": (2000, 0, 0, 0, 4004, 0, 2),
        "1_emax_sum": 1133182.070172505,
        "1_fillage": 1.0,
        "1_load_sum": 61670503.56088841,
        "1_mprl": 19485.136175954398,
        "1_pprl": 42234.650647466595,
        "1_pump_load_sum": 7300444.683982859,
        "1_pump_pos_sum": 1864.872283435399,
        "1_pump_stroke": 2.2335627143262706,
        "1_pump_vel_abs": 895.7596141187579,
        "1_pumped": 0.003385723569173207,
        "1_work": 56998.288582677946,
    },
    "velocity": {"counts": (757, 43, 0), "load_sum": 25169742.361869745, "pprl": 50191.30579975226},
}


def _check(got: dict, want: dict) -> None:
    assert got.keys() == want.keys()
    for key, w in want.items():
        if isinstance(w, float):
            assert got[key] == pytest.approx(w, rel=1e-10, abs=1e-12), key
        else:
            assert got[key] == w, key


@pytest.mark.parametrize("case", sorted(CASES))
def test_trajectories_match_the_pre_refactor_kernel(case: str) -> None:
    _check(figures(case), REFERENCE[case])


def test_spring_block_and_run_velocity_match_the_pre_refactor_kernel() -> None:
    _check(hopf_figures(), REFERENCE["hopf"])
    _check(velocity_figures(), REFERENCE["velocity"])
