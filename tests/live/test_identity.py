"""The live MMSI split and AIS anomaly flags (causal) against ``seatrack fuse``'s batch
split (:func:`seatrack.fusion.anomalies.split_identities`) on the same reports."""

from __future__ import annotations

import numpy as np

from seatrack.fusion import scenario as sc
from seatrack.fusion.anomalies import gap_limits
from seatrack.fusion.anomalies import reporting_gaps
from seatrack.fusion.anomalies import split_identities
from seatrack.fusion.associate import FusionConfig
from seatrack.fusion.coverage import Coverage
from seatrack.fusion.picture import prepare_ais
from seatrack.io.radar import parse_radar_config
from seatrack.live.identity import LiveIdentities
from seatrack.live.identity import split_key
from seatrack.live.identity import vessel_key

T0, ORIGIN = 1.7e9, (56.0, 7.0)


def scene():
    """Six vessels for 1,200 s: 0 and 1 share an MMSI, 2 is spoofed 3 km away from 400 s
    on, 3 is silent for 200 s, 4 sends one wild report; time order."""
    start = np.array([[-6000, 0], [6000, 2000], [0, -6000.0], [3000, 3000], [-3000, -3000],
                      [0, 6000.0]])  # fmt: skip
    truth = sc.straight_truth(start, np.array([90, 270, 0, 45, 135, 180.0]),
                              np.full(6, 10.0), T0, 1200)  # fmt: skip
    corr = sc.Corruption(shared=((0, 1),), spoof=(2,), spoof_offset=((3000.0, 0.0),),
                         spoof_start=(T0 + 400,), spoof_end=(T0 + 2000,), silent=(3,),
                         silent_start=(T0 + 500,), silent_end=(T0 + 700,))  # fmt: skip
    rep, _ = sc.ais_reports(truth, np.full(6, 10.0), ORIGIN, corr, 10.0,
                            np.random.default_rng(4))  # fmt: skip
    wild = np.flatnonzero(rep.mmsi == truth.mmsi[4])[40]
    rep.lat[wild] += 0.2  # 22 km north, once
    return rep


def batch_flags(rep):
    """``seatrack fuse``'s split and flags (``prepare_ais``); its ``jump`` without the
    reports its AIS filter rejects (they are the live filter's ``status``)."""
    cov = Coverage.of(parse_radar_config({"lat_deg": 56.0, "lon_deg": 7.0}).site, land=False)
    xy = cov.to_local(rep.lat, rep.lon)
    s = split_identities(rep.mmsi, rep.t, xy, rep.sog_kn, rep.cog_deg)
    use = s.vessel >= 0
    limit = gap_limits(s.vessel[use], rep.t[use], s.vessel_mmsi.size, 2.5, 30.0)
    gap = reporting_gaps(np.where(use, s.vessel, -1), rep.t, limit)
    side = prepare_ais(rep, cov, FusionConfig())  # the fuse path: the same split and flags
    assert side.rows.size == len(rep) and np.array_equal(side.vessel, s.vessel)
    assert np.array_equal(side.gap, gap) and np.array_equal(side.conflict, s.conflict)
    assert not (s.jump & ~side.jump).any()
    return np.where(use, s.sub, -1), gap, s.jump, s.conflict


def live_flags(rep):
    ids = LiveIdentities(ORIGIN, 2.5, 30.0, record=True)
    rows = np.stack([rep.t, rep.lat, rep.lon, rep.sog_kn, rep.cog_deg], -1)
    keys = np.concatenate([ids.route(rep.mmsi[k : k + 7], rows[k : k + 7])
                           for k in range(0, len(rep), 7)])  # fmt: skip
    ids.finish()
    by = {(m, t): (s, g, j, c) for m, t, s, g, j, c in ids.log}
    assert len(by) == len(ids.log) == len(rep)  # every report decided once
    got = np.array([by[m, t] for m, t in zip(rep.mmsi.tolist(), rep.t.tolist(), strict=True)])
    return got[:, 0].astype(int), *(got[:, k].astype(bool) for k in (1, 2, 3)), keys, ids


def test_live_split_and_flags_agree_with_the_batch():
    rep = scene()
    sub, gap, jump, conflict = batch_flags(rep)
    lsub, lgap, ljump, lconflict, keys, ids = live_flags(rep)
    # the scene has every anomaly
    assert gap.any() and jump.sum() >= 2 and conflict.sum() > 100 and (sub == 1).sum() > 50
    np.testing.assert_array_equal(lsub, sub)  # every report to the same vessel
    np.testing.assert_array_equal(ljump, jump)
    np.testing.assert_array_equal(lgap, gap)
    # conflict: the batch flags both vessels' whole reports; live a report is flagged
    # from the moment both vessels are known (the second one's min_reports-th report)
    assert not (lconflict & ~conflict).any()
    shared = int(rep.mmsi[conflict][0])
    mine = rep.mmsi == shared
    known = np.sort(rep.t[mine & (sub == 1)])[2]
    np.testing.assert_array_equal(lconflict[mine & (rep.t >= known)],
                                  conflict[mine & (rep.t >= known)])  # fmt: skip
    assert (conflict & ~lconflict).sum() == (mine & (rep.t < known) & (sub == 0)).sum()
    # the reports went to their vessels' keys, held ones to the MMSI's tracked vessel
    own = [vessel_key(m, max(s, 0)) for m, s in zip(rep.mmsi.tolist(), sub, strict=True)]
    tracked = (sub >= 0) & (keys == np.array(own))
    # all but the wild report and the first two of each of the two further vessels
    assert tracked.sum() == len(rep) - 5
    assert {split_key(k) for k in keys} == {(int(m), 0) for m in np.unique(rep.mmsi)} | {
        (shared, 1),
        (int(rep.mmsi[jump & (sub == 1)][0]), 1),
    }
    assert ids.counts["identity_conflict"] == lconflict.sum()


def test_flags_shown_on_the_vessel_and_keys():
    ids = LiveIdentities(ORIGIN)
    t = T0 + 10.0 * np.arange(6)
    lat = np.full(6, 56.01)
    lon = 7.0 + 1e-4 * np.arange(6)
    lat[3] += 0.3  # one wild report: held, shown as a jump of the vessel
    rows = np.stack([t, lat, lon, np.full(6, 2.0), np.full(6, 90.0)], -1)
    keys = ids.route(np.full(6, 219000001), rows)
    assert keys.tolist() == [219000001] * 6
    assert ids.describe(219000001) == {"sub": 0, "gap": False, "jump": False,
                                       "identity_conflict": False}  # fmt: skip
    ids.route(np.array([219000001]), np.array([[T0 + 200, 56.01, 7.0006, 2.0, 90.0]]))
    assert ids.describe(219000001)["gap"]  # 140 s silent at 10 s reports
    assert vessel_key(219000001, 2) == 2219000001 and split_key(2219000001) == (219000001, 2)


def test_a_shared_mmsi_becomes_two_ais_features_over_udp():
    """A live process fed the scene's shared MMSI over UDP shows two AIS vessels,
    ``ais:MMSI`` and ``ais:MMSI#2``, both in identity conflict, and counts the flags."""
    import asyncio

    from live.streams import started
    from live.streams import udp_send
    from live.streams import wait_for
    from seatrack.live.nmea import encode_report
    from seatrack.live.process import LiveOptions
    from seatrack.live.sources import Source

    rep = scene()
    shared = int(np.bincount(rep.mmsi - rep.mmsi.min()).argmax() + rep.mmsi.min())
    k = np.flatnonzero(rep.mmsi == shared)[:60]
    lines = [s for i in k for s in encode_report(shared, float(rep.t[i]), float(rep.lat[i]),
             float(rep.lon[i]), float(rep.sog_kn[i]), float(rep.cog_deg[i]))]  # fmt: skip

    async def go():
        proc = await started(LiveOptions(ais=[Source("udp", "127.0.0.1", 0)]))
        for j in range(0, len(lines), 10):
            udp_send(proc.udp_ports[0], [b"\n".join(lines[j : j + 10])])
            await asyncio.sleep(0.002)
        await wait_for(lambda: proc.counters.received == len(lines))
        await proc.drain()
        feats = proc.picture.collection()["features"]
        health = proc.health()
        await proc.stop()
        return feats, health

    feats, health = asyncio.run(asyncio.wait_for(go(), 20))
    props = {f["id"]: f["properties"] for f in feats}
    assert set(props) == {f"ais:{shared}", f"ais:{shared}#2"}
    assert [props[f"ais:{shared}"]["sub"], props[f"ais:{shared}#2"]["sub"]] == [0, 1]
    assert all(p["mmsi"] == shared and p["identity_conflict"] for p in props.values())
    assert not any(p["gap"] or p["jump"] for p in props.values())
    assert health["ais_flags"]["identity_conflict"] > 0 and health["decoded"] == len(lines)
