#!/usr/bin/env python3
"""Smoke test of `peritwin-bench prognostics` (bench/prognostics_bench.cpp) with tiny settings:
B1 at dx = 2.5 mm (600 nodes), 8 particles. Checks the JSON lines' keys, that the numbers are sane
(coverages in [0, 1], errors >= 0, percentiles in order, times >= 0), and that the fixed seeds
make a trial reproducible and independent of the number of trials (trial 0 of a run of 2 and of a
run of 1 agree in every number but the wall times).

usage: check_prognostics_bench.py PERITWIN_BENCH"""
import json
import subprocess
import sys

TINY = ["prognostics", "--dx", "0.0025", "--particles", "8"]


def run(bench, trials):
    out = subprocess.run([bench, *TINY, "--trials", str(trials)], check=True,
                         capture_output=True, text=True, timeout=600).stdout
    lines = [json.loads(line) for line in out.splitlines() if line.strip()]
    assert len(lines) == trials + 1, f"{len(lines)} lines for {trials} trials:\n{out}"
    assert all(line["bench"] == "prognostics-trial" for line in lines[:-1]), lines
    assert lines[-1]["bench"] == "prognostics", lines[-1]
    return lines[:-1], lines[-1]


def check_trial(t):
    for key in ("trial", "truth", "inspections", "updates", "estimates", "alpha_lambda",
                "create_s", "apply_s", "applied_cycles", "truth_s", "wall_s"):
        assert key in t, f"trial line without {key}: {t}"
    truth = t["truth"]["end_of_life"]
    assert truth > 0, t
    assert t["truth"]["a2_factor"] > 0 and t["truth"]["load_scale"] > 0, t
    assert 1 <= len(t["inspections"]) <= 3, t
    for i in t["inspections"]:
        assert 0 < i["cycle"] < truth and i["truth_m"] >= 0, i
        assert i["kind"] in ("crack_length", "no_crack"), i
        if i["kind"] == "crack_length":
            assert i["measured_m"] >= 0, i
    for u in t["updates"]:
        assert u["wall_s"] >= 0 and "refused" not in u, u
        assert 0 < u["ess"] <= 8, u
    kinds = [e["kind"] for e in t["estimates"]]
    assert kinds[0] == "prior" and kinds.count("inspection") == len(t["updates"]), kinds
    assert kinds.count("lambda") <= 1, kinds
    for e in t["estimates"]:
        assert e["p05"] <= e["p50"] <= e["p95"], e
        assert e["relative_error"] >= 0 and e["wall_s"] >= 0, e
        assert e["covers"] == (e["p05"] <= truth <= e["p95"]), e
        assert e["a2"]["median"] > 0 and e["load_scale"]["median"] > 0, e
    al = t["alpha_lambda"]
    assert al is not None and 0 <= al["probability_in_bounds"] <= 1, al
    assert al["lower"] <= truth <= al["upper"], al
    for key in ("create_s", "apply_s", "truth_s", "wall_s"):
        assert t[key] >= 0, (key, t)


def check_summary(s, trials):
    assert s["trials"] == trials and s["valid_trials"] == trials, s
    assert s["particles"] == 8 and s["nodes"] > 0 and s["bonds"] > 0, s
    assert s["nominal_life"] > 0, s
    assert len(s["coverage_90"]) == len(s["median_relative_error"]) == 4, s
    assert s["trials_per_stage"][0] == trials, s
    for n, c, e in zip(s["trials_per_stage"], s["coverage_90"], s["median_relative_error"]):
        if n > 0:
            assert 0 <= c <= 1 and e >= 0, s
    assert 0 <= s["coverage_90_final"] <= 1 and s["median_relative_error_final"] >= 0, s
    al = s["alpha_lambda"]
    assert al["alpha"] == 0.2 and al["lambda"] == 0.5 and al["defined"] == trials, al
    assert 0 <= al["fraction_met"] <= 1, al
    for key in ("observe_s", "estimate_s"):
        assert s[key]["count"] > 0 and 0 <= s[key]["mean"] <= s[key]["max"], (key, s)
    assert s["estimate_s"]["count"] >= 2 * trials, s
    assert s["peak_rss_mb"] > 0 and s["wall_s"] >= 0, s
    for key in ("after_inspections", "trials", "median_error_le_0.10", "coverage_ge_0.80",
                "prior_coverage_ge_0.80"):
        assert key in s["goals"], s


def without_times(value):
    if isinstance(value, dict):
        return {k: without_times(v) for k, v in value.items()
                if not (k.endswith("_s") or k == "wall_s")}
    if isinstance(value, list):
        return [without_times(v) for v in value]
    return value


def main():
    bench = sys.argv[1]
    trials, summary = run(bench, 2)
    for t in trials:
        check_trial(t)
    check_summary(summary, 2)
    assert trials[0]["truth"] != trials[1]["truth"], "two trials drew the same truth"
    again, _ = run(bench, 1)
    assert without_times(again[0]) == without_times(trials[0]), (again[0], trials[0])
    print("ok: peritwin-bench prognostics, 2 trials x 8 particles, reproducible")


if __name__ == "__main__":
    main()
