/* seatrack track map: draws the JSON in #seatrack-data with Leaflet (see report/map_page.py).
 * Exposes what it drew as data attributes, for people and for headless-browser tests:
 * <body data-vessels data-paths data-vertices data-reports data-outliers data-land data-tiles>
 * and one <li class="vessel" data-mmsi data-parts data-vertices data-reports data-outliers>
 * per vessel; data-selected (MMSI) and data-shown (vessels passing the search) follow the
 * user. */
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("seatrack-data").textContent);
  var body = document.body, E5 = 1e-5;

  function undelta(a, scale) {
    var out = new Float64Array(a.length), c = 0;
    for (var i = 0; i < a.length; i++) { c += a[i]; out[i] = c * scale; }
    return out;
  }
  function fmt(n) { return Number(n).toLocaleString("en-US"); }
  function utc(t) { return new Date((D.t0 + t) * 1000).toISOString().slice(0, 19).replace("T", " "); }

  var la = undelta(D.la, E5), lo = undelta(D.lo, E5), tt = undelta(D.tt, 1);
  var rla = undelta(D.rla, E5), rlo = undelta(D.rlo, E5);
  var ola = undelta(D.ola, E5), olo = undelta(D.olo, E5), ot = undelta(D.ot, 1);
  var nv = D.mmsi.length;
  // SVG paths (one DOM element per vessel) for small maps, one canvas for large ones
  var svg = la.length <= 60000 && nv <= 3000;
  var map = L.map("map", { preferCanvas: true, maxZoom: 19, zoomSnap: 0.25 });
  var canvasR = L.canvas({ padding: 0.5 });
  var trackR = svg ? L.svg({ padding: 0.5 }) : canvasR;
  if (D.view) map.fitBounds(D.view, { padding: [16, 16], maxZoom: 15 });
  else map.setView([0, 0], 2);

  // --- Natural Earth land, under the tiles: what an offline browser shows
  map.createPane("land").style.zIndex = 150;
  var nLand = 0;
  if (D.land) {
    var landR = L.canvas({ pane: "land", padding: 0.5 });
    var qa = undelta(D.land.la, 1), qo = undelta(D.land.lo, 1), box = D.land.box, off = D.land.off;
    var rings = [], coast = [];
    var onBox = function (i, j) {  // edge i-j runs along the clip box, not along a coast
      return (qo[i] === box[0] && qo[j] === box[0]) || (qo[i] === box[2] && qo[j] === box[2]) ||
             (qa[i] === box[1] && qa[j] === box[1]) || (qa[i] === box[3] && qa[j] === box[3]);
    };
    for (var k = 0; k + 1 < off.length; k++) {
      var ring = [], run = [];
      for (var i = off[k]; i < off[k + 1]; i++) {
        var j = i + 1 < off[k + 1] ? i + 1 : off[k];
        ring.push([qa[i] * E5, qo[i] * E5]);
        if (onBox(i, j)) { if (run.length) { coast.push(run); run = []; } continue; }
        if (!run.length) run.push([qa[i] * E5, qo[i] * E5]);
        run.push([qa[j] * E5, qo[j] * E5]);
      }
      if (run.length) coast.push(run);
      rings.push(ring);
    }
    nLand = rings.length;
    if (rings.length) {
      L.polygon(rings, { renderer: landR, stroke: false, fillColor: "#f1ede3", fillOpacity: 1,
        interactive: false }).addTo(map);
      L.polyline(coast, { renderer: landR, color: "#8f8774", weight: 0.9, interactive: false })
        .addTo(map);
    }
  }

  // --- online tiles: OpenStreetMap (or the page's tile_url) and OpenSeaMap seamarks.
  // OpenStreetMap's tile usage policy requires a Referer, which a page opened from disk
  // (file://) cannot send: such a page asks OSM for nothing and says how to get the tiles.
  var note = document.getElementById("tilenote");
  function showNote(text) { note.textContent = text; note.hidden = false; }
  var bases = {}, overlays = {}, tileOpts = { maxZoom: 19, referrerPolicy: "strict-origin-when-cross-origin" };
  body.dataset.tiles = "off";
  if (D.tiles && D.tiles.needs_referer && location.protocol === "file:") {
    body.dataset.tiles = "needs-http";
    showNote("OpenStreetMap tiles need this page served over http(s) (their usage policy " +
      "requires a Referer, which a file opened from disk does not send), e.g. by " +
      "python -m http.server in its folder. Showing the Natural Earth coastline carried " +
      "in this page.");
  } else if (D.tiles) {
    var loaded = 0, failed = 0;
    var base = L.tileLayer(D.tiles.base, L.extend({ attribution: D.tiles.base_attribution }, tileOpts));
    var tilesState = function () {
      body.dataset.tiles = loaded ? (failed ? "partial" : "loaded") : (failed ? "failed" : "waiting");
      if (!loaded && failed) {
        showNote("Map tiles could not be loaded (the browser seems offline): " +
          "showing the Natural Earth coastline carried in this page.");
      } else if (loaded) note.hidden = true;
    };
    base.on("tileload", function () { loaded++; tilesState(); });
    base.on("tileerror", function () { failed++; tilesState(); });
    tilesState();
    base.addTo(map);
    bases[D.tiles.needs_referer ? "OpenStreetMap" : "Tiles"] = base;
    bases["Natural Earth coastline only"] = L.layerGroup();
  }
  if (D.tiles && D.tiles.seamarks) {
    overlays["OpenSeaMap seamarks"] = L.tileLayer(D.tiles.seamarks,
      L.extend({ attribution: D.tiles.seamark_attribution }, tileOpts)).addTo(map);
  }
  map.attributionControl.addAttribution("coast: Natural Earth (public domain)");

  // --- tracks: one polyline (one part per track segment) per vessel
  function colour(v) { return "hsl(" + (20 + (200 + v * 137.508) % 320) + ",72%,38%)"; }  // no reds
  var tracks = new Array(nv), trackGroup = L.featureGroup().addTo(map), paths = 0;
  var outGroups = new Array(nv), outGroup = L.layerGroup().addTo(map);
  var sel = -1;
  for (var v = 0; v < nv; v++) {
    var parts = [];
    for (var p = D.vpart[v]; p < D.vpart[v + 1]; p++) {
      var pts = [];
      for (var q = D.poff[p]; q < D.poff[p + 1]; q++) pts.push([la[q], lo[q]]);
      parts.push(pts);
    }
    if (parts.length) {
      var pl = L.polyline(parts, { renderer: trackR, color: colour(v), weight: 2, opacity: 0.9,
        className: "st-track st-v" + D.mmsi[v] });
      pl.bindTooltip(String(D.mmsi[v]), { sticky: true });
      pl.on("click", (function (w) { return function () { select(w, false); }; })(v));
      tracks[v] = pl;
      trackGroup.addLayer(pl);
      paths++;
    }
    var g = L.layerGroup();
    for (var o = D.ov[v]; o < D.ov[v + 1]; o++) {
      g.addLayer(L.circleMarker([ola[o], olo[o]], { renderer: canvasR, radius: 1.8, stroke: false,
        fillColor: "#e0282e", fillOpacity: 0.85, interactive: false }));
    }
    outGroups[v] = g;
    outGroup.addLayer(g);
  }

  // --- the vessel list, search and selection
  var ul = document.getElementById("vessels"), items = new Array(nv);
  var frag = document.createDocumentFragment();
  for (v = 0; v < nv; v++) {
    var li = document.createElement("li"), nOut = D.noutliers[v];
    li.className = "vessel";
    li.dataset.mmsi = D.mmsi[v];
    li.dataset.parts = D.vpart[v + 1] - D.vpart[v];
    li.dataset.vertices = D.poff[D.vpart[v + 1]] - D.poff[D.vpart[v]];
    li.dataset.reports = D.rv[v + 1] - D.rv[v];
    li.dataset.outliers = D.ov[v + 1] - D.ov[v];
    li.innerHTML = '<span class="sw line"></span><span class="m"></span>' +
      '<span class="n"></span>' + (nOut ? '<span class="o"></span>' : "");
    li.firstChild.style.background = colour(v);
    li.children[1].textContent = D.mmsi[v];
    li.children[2].textContent = fmt(D.nusable[v]) + " rep.";
    if (nOut) li.children[3].textContent = fmt(nOut) + " out";
    li.addEventListener("click", (function (w) { return function () { select(w, true); }; })(v));
    items[v] = li;
    frag.appendChild(li);
  }
  ul.appendChild(frag);

  var selLayer = L.layerGroup().addTo(map);
  function restyle() {
    for (var w = 0; w < nv; w++) {
      if (!tracks[w]) continue;
      tracks[w].setStyle({ weight: w === sel ? 4 : 2, opacity: sel < 0 || w === sel ? 0.9 : 0.3 });
    }
    if (sel >= 0 && tracks[sel]) tracks[sel].bringToFront();
  }
  function select(v, zoom) {
    if (sel >= 0) items[sel].classList.remove("selected");
    selLayer.clearLayers();
    if (sel === v && !zoom) { sel = -1; restyle(); delete body.dataset.selected; return; }
    sel = v;
    items[v].classList.add("selected");
    items[v].scrollIntoView({ block: "nearest" });
    body.dataset.selected = D.mmsi[v];
    var b = L.latLngBounds([]);
    for (var r = D.rv[v]; r < D.rv[v + 1]; r++) {
      selLayer.addLayer(L.circleMarker([rla[r], rlo[r]], { renderer: canvasR, radius: 2.2,
        color: "#27313b", weight: 1, fillColor: "#fff", fillOpacity: 1, interactive: false }));
      b.extend([rla[r], rlo[r]]);
    }
    for (var o = D.ov[v]; o < D.ov[v + 1]; o++) {
      selLayer.addLayer(L.circleMarker([ola[o], olo[o]], { renderer: canvasR, radius: 3.5,
        color: "#fff", weight: 1, fillColor: "#e0282e", fillOpacity: 1 })
        .bindTooltip("outlier " + utc(ot[o]) + " UTC"));
    }
    if (tracks[v]) b = tracks[v].getBounds();
    restyle();
    if (zoom && b.isValid()) map.fitBounds(b.pad(0.08), { maxZoom: 15 });
  }

  var search = document.getElementById("search"), count = document.getElementById("count");
  var shown = new Array(nv).fill(true);
  function filter() {
    var s = search.value.replace(/\D/g, ""), n = 0;
    for (var w = 0; w < nv; w++) {
      var show = !s || String(D.mmsi[w]).indexOf(s) >= 0;
      if (show) n++;
      if (show === shown[w]) continue;
      shown[w] = show;
      items[w].hidden = !show;
      if (tracks[w]) { if (show) trackGroup.addLayer(tracks[w]); else trackGroup.removeLayer(tracks[w]); }
      if (show) outGroup.addLayer(outGroups[w]); else outGroup.removeLayer(outGroups[w]);
    }
    count.textContent = (n === nv ? fmt(nv) : fmt(n) + " of " + fmt(nv)) + " vessels";
    body.dataset.shown = n;
  }
  search.addEventListener("input", filter);
  search.addEventListener("keydown", function (e) {
    if (e.key !== "Enter") return;
    for (var w = 0; w < nv; w++) if (shown[w]) { select(w, true); return; }
  });
  function home() {
    if (sel >= 0) select(sel, false);
    if (D.view) map.fitBounds(D.view, { padding: [16, 16], maxZoom: 15 });
  }
  document.getElementById("showall").addEventListener("click", function () {
    search.value = ""; filter(); home();
  });
  filter();

  // --- positions at a chosen time (optional time slider)
  var tmin = Infinity, tmax = -Infinity;
  for (var z = 0; z < tt.length; z++) { if (tt[z] < tmin) tmin = tt[z]; if (tt[z] > tmax) tmax = tt[z]; }
  var posLayer = L.layerGroup(), marks = new Array(nv);
  function positionsAt(t) {
    posLayer.clearLayers();
    for (var w = 0; w < nv; w++) {
      if (!shown[w]) continue;
      for (var p = D.vpart[w]; p < D.vpart[w + 1]; p++) {
        var a = D.poff[p], b = D.poff[p + 1] - 1;
        if (b < a || t < tt[a] || t > tt[b]) continue;
        while (b - a > 1) { var m = (a + b) >> 1; if (tt[m] <= t) a = m; else b = m; }
        var f = tt[b] > tt[a] ? (t - tt[a]) / (tt[b] - tt[a]) : 0;
        var ll = [la[a] + f * (la[b] - la[a]), lo[a] + f * (lo[b] - lo[a])];
        if (!marks[w]) marks[w] = L.circleMarker(ll, { renderer: canvasR, radius: 4.5, color: "#fff",
          weight: 1.2, fillColor: colour(w), fillOpacity: 1 }).bindTooltip(String(D.mmsi[w]));
        else marks[w].setLatLng(ll);
        posLayer.addLayer(marks[w]);
        break;
      }
    }
  }
  if (tt.length && tmax > tmin) {
    var ctl = L.control({ position: "bottomleft" });
    ctl.onAdd = function () {
      var div = L.DomUtil.create("div", "st-time");
      div.innerHTML = '<label><input type="checkbox" id="tcheck"> positions at</label> ' +
        '<input type="range" id="trange" min="0" max="1000" value="0"> <span id="tlabel"></span>';
      L.DomEvent.disableClickPropagation(div);
      L.DomEvent.disableScrollPropagation(div);
      return div;
    };
    ctl.addTo(map);
    var check = document.getElementById("tcheck"), range = document.getElementById("trange");
    var label = document.getElementById("tlabel");
    var onTime = function () {
      var t = tmin + (tmax - tmin) * range.value / 1000;
      label.textContent = utc(t) + " UTC";
      if (check.checked) { positionsAt(t); posLayer.addTo(map); } else map.removeLayer(posLayer);
    };
    range.addEventListener("input", function () { check.checked = true; onTime(); });
    check.addEventListener("change", onTime);
    search.addEventListener("input", function () { if (check.checked) onTime(); });
    onTime();
    overlays["Positions at time"] = posLayer;
  }

  overlays["Tracks"] = trackGroup;
  overlays["Outliers"] = outGroup;
  L.control.layers(bases, overlays, { collapsed: true }).addTo(map);
  L.control.scale({ imperial: false }).addTo(map);

  // --- links: page.html#q=2190 filters the list, page.html#mmsi=219000001 selects a vessel
  function fromHash() {
    var h = decodeURIComponent(location.hash.slice(1)), m = /(?:^|&)q=(\d*)/.exec(h);
    if (m) { search.value = m[1]; filter(); }
    m = /(?:^|&)mmsi=(\d+)/.exec(h);
    if (m) { var w = D.mmsi.indexOf(Number(m[1])); if (w >= 0 && w !== sel) select(w, true); }
  }
  window.addEventListener("hashchange", fromHash);
  fromHash();

  // --- what was drawn, in words and as attributes
  var S = D.stats, txt = "Drawn: " + fmt(paths) + " tracks, " + fmt(S.vertices) + " of " +
    fmt(S.track_points) + " smoothed positions";
  txt += S.vertices < S.track_points ? " (Douglas-Peucker, tolerance " + S.tolerance_m + " m)" : "";
  txt += "; " + fmt(S.outliers_drawn) + " of " + fmt(S.outliers) + " outliers" +
    (S.outlier_stride > 1 ? " (1 in " + S.outlier_stride + ")" : "");
  txt += "; reports of the selected vessel" +
    (S.report_stride > 1 ? " (1 in " + S.report_stride + ")" : "") + ".";
  txt += D.tiles ? " Background: online tiles when they load, else Natural Earth land." :
    " Background: Natural Earth land (no online tiles).";
  document.getElementById("drawn").textContent = txt;
  body.dataset.vessels = items.length;
  body.dataset.paths = paths;
  body.dataset.vertices = la.length;
  body.dataset.reports = rla.length;
  body.dataset.outliers = ola.length;
  body.dataset.land = nLand;
  body.dataset.renderer = svg ? "svg" : "canvas";
})();
