"""The leads' ramp room (timing.lead_length): the sin² law's distance from rest to the
process speed, kept per (v, a_max, j_max)."""

from offline_prog.timing.lead_length import ramp_length_m


def test_a_kept_ramp_is_the_fresh_one_for_each_changed_input():
    """Each input changed in turn after a first call: the kept result is the one
    computed afresh (bit for bit), and it differs from the first (the cache is keyed on
    every input the ramp depends on)."""
    base = dict(v=0.1, a_max=1.0, j_max=20.0)
    first = ramp_length_m(base["v"], a_max=base["a_max"], j_max=base["j_max"])
    for key, value in (("v", 0.05), ("a_max", 0.5), ("j_max", 5.0)):
        args = base | {key: value}
        kept = ramp_length_m(args["v"], a_max=args["a_max"], j_max=args["j_max"])
        fresh = ramp_length_m.__wrapped__(args["v"], a_max=args["a_max"], j_max=args["j_max"])
        assert kept == fresh, key
        assert kept != first, key
