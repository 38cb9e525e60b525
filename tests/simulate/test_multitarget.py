def test_work_samples_count_truth_and_scans_of_every_target():
    from types import SimpleNamespace

    from seatrack.simulate.multitarget import work_samples

    radar = SimpleNamespace(scan_period=2.0)
    # 101 scans + 201 truth samples, of 3 targets and the own ship
    assert work_samples(200.0, 1.0, 3, [radar]) == (101 + 201) * 4
