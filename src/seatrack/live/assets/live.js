/* seatrack live map: the picture from /ws (GeoJSON points of AIS vessels and radar tracks)
 * drawn with Leaflet: a dot, a heading vector (the distance run in VECTOR_S seconds) and
 * a short trail per track; click for details. Online: OSM tiles and OpenSeaMap seamarks;
 * offline: the Natural Earth coast from /api/land under them.
 * For people and tests: <body data-ais data-radar data-updates> and, per marker, an
 * element .st-live with data-id, data-lat, data-lon, data-class (radar-AIS fusion). */
(function () {
  "use strict";
  var VECTOR_S = 180, KN = 0.514444, R = 6371000;
  var body = document.body;
  var map = L.map("map", { preferCanvas: false, maxZoom: 19 }).setView([0, 0], 2);
  map.createPane("land").style.zIndex = 150;
  L.tileLayer("https://tile.openstreetmap.org/{z}/{x}/{y}.png", {
    maxZoom: 19, attribution: '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a>'
  }).addTo(map);
  L.tileLayer("https://tiles.openseamap.org/seamark/{z}/{x}/{y}.png", {
    maxZoom: 18, attribution: '&copy; <a href="https://www.openseamap.org">OpenSeaMap</a>'
  }).addTo(map);
  var items = {}, fitted = false, landLoaded = false, updates = 0;

  function ahead(lat, lon, cogDeg, dist) {
    var c = cogDeg * Math.PI / 180;
    return [lat + dist * Math.cos(c) / R * 180 / Math.PI,
            lon + dist * Math.sin(c) / (R * Math.cos(lat * Math.PI / 180)) * 180 / Math.PI];
  }
  function popup(p) {
    var rows = [["id", p.id], ["source", p.source], ["MMSI", p.mmsi], ["name", p.name],
      ["time (UTC)", p.time_utc], ["SOG (kn)", p.sog_kn], ["COG (deg)", p.cog_deg],
      ["status", p.status], ["sigma (m)", p.std_m], ["class", p["class"]],
      ["identity prob.", p.identity_prob], ["not seen", p.not_seen ? "yes" : null],
      ["AIS vessel", p.ais_id], ["gap", p.gap ? "yes" : null], ["jump", p.jump ? "yes" : null],
      ["identity conflict", p.identity_conflict ? "yes" : null]];
    return '<table class="popup">' + rows.filter(function (r) { return r[1] !== null && r[1] !== ""; })
      .map(function (r) { return "<tr><td>" + r[0] + "</td><td>" + String(r[1]) + "</td></tr>"; })
      .join("") + "</table>";
  }
  /* radar: red, dark (no AIS) magenta, with AIS green; AIS: blue, not seen orange */
  function colorOf(p) {
    if (p.source === "radar") {
      return p["class"] === "dark" ? "#d0168a" : p["class"] === "ais" ? "#1e8449" : "#c0392b";
    }
    return p.not_seen ? "#e67e22" : "#1f5fa8";
  }
  function draw(f) {
    var p = f.properties, c = f.geometry.coordinates, lat = c[1], lon = c[0];
    if (lat === null || lon === null) return;
    var color = colorOf(p);
    var it = items[p.id];
    if (!it) {
      it = items[p.id] = {
        dot: L.circleMarker([lat, lon], { radius: 5, color: color, weight: 2, fillOpacity: 0.8,
          className: "st-live" }).addTo(map),
        vec: L.polyline([], { color: color, weight: 2 }).addTo(map),
        trail: L.polyline([], { color: color, weight: 1, opacity: 0.5 }).addTo(map)
      };
      it.dot.bindPopup("");
    }
    it.dot.setStyle({ color: color }); it.vec.setStyle({ color: color });
    it.trail.setStyle({ color: color });
    it.dot.setLatLng([lat, lon]);
    it.dot.setPopupContent(popup(p));
    var el = it.dot.getElement && it.dot.getElement();
    if (el) {
      el.dataset.id = p.id; el.dataset.lat = lat; el.dataset.lon = lon;
      el.dataset.class = p["class"] || "";
    }
    var v = p.sog_kn && p.cog_deg !== null ? p.sog_kn * KN * VECTOR_S : 0;
    it.vec.setLatLngs(v > 0 ? [[lat, lon], ahead(lat, lon, p.cog_deg, v)] : []);
    it.trail.setLatLngs((p.trail || []).map(function (q) { return [q[1], q[0]]; }));
  }
  function remove(id) {
    var it = items[id];
    if (!it) return;
    map.removeLayer(it.dot); map.removeLayer(it.vec); map.removeLayer(it.trail);
    delete items[id];
  }
  function loadLand(b) {
    landLoaded = true;
    var box = [Math.max(-180, b.getWest() - 2), Math.max(-85, b.getSouth() - 2),
               Math.min(180, b.getEast() + 2), Math.min(85, b.getNorth() + 2)];
    fetch("/api/land?box=" + box.map(function (x) { return x.toFixed(4); }).join(","))
      .then(function (r) { return r.json(); })
      .then(function (g) {
        L.geoJSON(g, { pane: "land", interactive: false, style: { stroke: true, color: "#8f8774",
          weight: 0.8, fillColor: "#f1ede3", fillOpacity: 1 } }).addTo(map);
      }).catch(function () { landLoaded = false; });
  }
  function counts() {
    var a = 0, r = 0;
    for (var id in items) { if (id.indexOf("radar:") === 0) r++; else a++; }
    body.dataset.ais = a; body.dataset.radar = r; body.dataset.updates = updates;
    document.getElementById("counts").textContent = a + " vessels, " + r + " radar tracks";
  }
  function apply(msg) {
    if (msg.type === "health") {
      var h = msg.health;
      document.getElementById("status").textContent = "received " + h.received +
        ", rejected " + Object.values(h.rejected).reduce(function (s, x) { return s + x; }, 0) +
        ", p99 " + h.latency_ms.p99 + " ms";
      return;
    }
    if (msg.full) for (var id in items) remove(id);
    (msg.removed || []).forEach(remove);
    msg.features.forEach(draw);
    updates++;
    var ids = Object.keys(items);
    if (!fitted && ids.length) {
      var b = L.latLngBounds(ids.map(function (k) { return items[k].dot.getLatLng(); }));
      map.fitBounds(b.pad(0.2), { maxZoom: 13 });
      fitted = true;
      if (!landLoaded) loadLand(b);
    }
    counts();
  }
  function connect() {
    var ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
    ws.onopen = function () { document.getElementById("status").textContent = "connected"; };
    ws.onmessage = function (e) { apply(JSON.parse(e.data)); };
    ws.onclose = function () {
      document.getElementById("status").textContent = "reconnecting";
      setTimeout(connect, 1000);
    };
  }
  connect();
})();
