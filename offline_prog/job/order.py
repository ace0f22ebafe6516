# TEMPORARY stand-in (not committed): replaced by the order branch.
import dataclasses


@dataclasses.dataclass
class JobOrder:
    sequence: list
    air_time_s: float = 0.0
    given_air_time_s: float = 0.0
    saved_s: float = 0.0
    method: str = "given"


def order_job(options, q_home, *, qd_max, qdd_max, n_seams, mode, controller_joints=None):
    seq, seen = [], set()
    for i, o in enumerate(options):
        if o[0] not in seen:
            seen.add(o[0])
            seq.append(i)
    return JobOrder(seq)
