"""The kernels' records (flexsat.sim.kernel_arrays): the output arrays are case-major, with a
time length of 0 for what is not recorded, and every case starts as "not stopped"."""

import numpy as np

from flexsat.sim.kernel_arrays import RECORDS, Records, allocate_records, case_index


def test_records_are_case_major_and_empty_where_nothing_is_recorded():
    rec = allocate_records(50, 3, 6, 2, 4, record_states=False, r=0, energy=False)
    assert isinstance(rec, Records) and rec._fields == RECORDS
    assert rec.X.shape == (3, 0, 6) and rec.Y.shape == (3, 50, 4)
    assert rec.Ucmd.shape == rec.U.shape == rec.D.shape == (3, 50, 2)
    assert rec.F.shape == (3, 50) and rec.O.shape == (3, 0, 0) and rec.En.shape == (3, 0)
    assert rec.stop.dtype == np.int64 and np.all(rec.stop == -1)
    full = allocate_records(50, 3, 6, 2, 4, record_states=True, r=5, energy=True)
    assert full.X.shape == (3, 50, 6) and full.O.shape == (3, 50, 5) and full.En.shape == (3, 50)


def test_a_shared_axis_is_read_at_0_and_a_per_case_axis_at_the_case():
    assert [case_index(1, c) for c in range(4)] == [0, 0, 0, 0]
    assert [case_index(4, c) for c in range(4)] == [0, 1, 2, 3]
