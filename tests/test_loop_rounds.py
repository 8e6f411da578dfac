"""Which candidates are kept, and which of those kept in a round goes in."""

from dataclasses import replace

from fosmodel.loop.effects import make
from fosmodel.loop.judge import Comparison, Judgement, verdict
from fosmodel.loop.rounds import Trial, choose


def _trial(effect, end, earlier):
    """A trial kept on the 30 min outage bias: its gain at the end and from earlier origins
    (None: an origin that could not judge it)."""
    def comparisons(gain):
        return (Comparison("one_step", None, 10, 0.01, None, 1.0, 5.0, 1e-6, 1.0),
                Comparison("outage", 1800.0, 9, gain, None, 1.0, 5.0, 1e-6, 1.0))

    judgement = Judgement(comparisons(end), (1.0, 2.0, 3.0, 4.0),
                          tuple(None if g is None else comparisons(g) for g in earlier),
                          "outage_1800s")
    return Trial(effect, None, None, judgement)


def test_the_kept_are_ranked_over_the_origins_that_judged_them_all():
    """A level gains most far from its data; a driver the early pasts cannot estimate is
    judged from the end only.  Over the end alone the driver gains more."""
    level = _trial(make("level", taus=(10.0,)), 0.81, [0.96, 0.92, 0.87])
    driver = _trial(make("driver", channel="temp_c", forms=[["pow(temp_c,1,15)", 5e-4]]),
                    0.88, [None, None, None])
    assert level.judgement.score() > driver.judgement.score()  # each over its own origins
    assert choose([level, driver]) is driver
    assert choose([driver, level]) is driver
    # judged from the same origins, the average over them decides as before
    judged = _trial(driver.effect, 0.88, [0.80, 0.82, 0.84])
    assert choose([level, judged]) is level
    # from the origins both were judged from
    partly = _trial(driver.effect, 0.80, [None, 0.95, 0.90])
    assert level.judgement.judged_from() & partly.judgement.judged_from() == {0, 1, 2}
    assert choose([level, partly]) is partly  # 0.883 against 0.867
    # over several sessions a level is judged on the held-out sessions only (one gain), a
    # drift ahead in time too (a gain per session, then the held-out one): their ends meet
    pooled = Judgement(level.judgement.last, (), None, "outage_1800s")
    ahead = _trial(make("drift", tau_s=100.0), 0.5, [0.99, 0.99, 0.99])
    assert pooled.judged_from() == {0} and ahead.judgement.score([0])[0] == 0.5


def test_a_function_of_time_is_not_kept_on_what_only_its_next_stretch_judged():
    """A step after every earlier origin, whose 30 min outages are too few to judge by halves:
    the evaluation right after its data is its only judge, and a stale constant passes there."""
    step = make("step", time_s=36_715.0)
    last = (Comparison("one_step", None, 10, 0.0, (0.003, -0.002), 0.1, 2.0, 0.016, 0.57),
            Comparison("outage", 300.0, 57, 0.126, (0.411, -1.047), 0.5, 4.0, 9e-5, 0.78),
            Comparison("outage", 1800.0, 9, 0.531, None, 0.9, 3.5, 0.0046, 0.87))
    assert verdict(last, None, 0.01, step.strict) == "outage_1800s"  # at the end alone
    assert verdict(last, [], 0.01, step.strict) is None  # and no earlier origin judged it
    judged = tuple(replace(c, gain=0.4) for c in last)
    assert verdict(last, [judged], 0.01, step.strict) == "outage_1800s"
    # a level holds still beyond its data: it needs no judge further away
    assert verdict(last, [], 0.01, make("level", taus=(10.0,)).strict) == "outage_1800s"
