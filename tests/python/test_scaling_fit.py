"""scripts/scaling_fit.py: the marginal relaxations of each search onto phi_J, counted from a run's
per-attempt CSV the way summary.json counts them (attempts of more than 1e5 force evaluations)."""
import importlib.util

from conftest import SOURCE_DIR

spec = importlib.util.spec_from_file_location("scaling_fit", SOURCE_DIR / "scripts" / "scaling_fit.py")
scaling_fit = importlib.util.module_from_spec(spec)
spec.loader.exec_module(scaling_fit)


def attempt(accepted, phase, evals):
    return {"accepted": str(int(accepted)), "phase": phase, "evals": str(evals)}


def test_a_search_runs_from_the_first_overshoot_to_the_next_accepted_state():
    tries = [attempt(1, "unjammed", 300), attempt(1, "unjammed", 250_000),  # the approach: in no search
             attempt(0, "unjammed", 9_000), attempt(0, "unjammed", 100_001), attempt(0, "unjammed", 100_000),
             attempt(1, "jammed", 400_000)]
    assert scaling_fit.marginal_per_search(tries) == [2]


def test_a_bracket_settled_below_the_window_starts_the_next_search():
    tries = [attempt(0, "unjammed", 200_000), attempt(1, "unjammed", 50),  # grows on from below the window
             attempt(1, "unjammed", 80), attempt(0, "unjammed", 10), attempt(0, "unjammed", 300_000),
             attempt(0, "unjammed", 300_000), attempt(1, "jammed", 20)]
    assert scaling_fit.marginal_per_search(tries) == [1, 2]


def test_trials_above_jamming_belong_to_no_search_and_an_unended_search_counts():
    tries = [attempt(0, "unjammed", 1), attempt(1, "jammed", 1), attempt(0, "jammed", 500_000),
             attempt(1, "jammed", 10)]
    assert scaling_fit.marginal_per_search(tries) == [0]
    assert scaling_fit.marginal_per_search([attempt(0, "unjammed", 150_000)]) == [1]
    assert scaling_fit.marginal_per_search([attempt(1, "unjammed", 150_000)]) == []


def test_no_exponent_is_read_from_runs_of_one_box_side():
    assert not scaling_fit.spans_sizes([1207, 1242, 1231])
    assert not scaling_fit.spans_sizes([1207])
    assert scaling_fit.spans_sizes([179, 1231])


def test_the_cost_lines_counters_are_read_and_an_older_output_without_them_is_none():
    txt = ("  cost     search trials    12  marginal relaxations   3  Newton factorisations     40  factor reuses     "
           "90  evals initial 5 search 7 above 9\n  active set steps 85  factorisations 162  updates 27365\n")
    assert scaling_fit.cost_counters(txt) == {
        "search_trials": 12, "marginal": 3, "newton_factorisations": 40,
        "active_set_steps": 85, "active_set_factorisations": 162, "active_set_updates": 27365}
    older = scaling_fit.cost_counters(txt.splitlines()[0])
    assert older["marginal"] == 3 and older["active_set_steps"] is None and older["active_set_updates"] is None
    assert set(scaling_fit.cost_counters("no cost line").values()) == {None}
