// shadowtiles inspector: a Leaflet (L.CRS.Simple) view of /v1/render tiles, the build's meta, texel
// popups (/v1/texel) and world-point queries (/v1/shadow). Plain JS, no build step.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const fmt = (x, digits = 4) => (x === null || x === undefined) ? '–' :
    (Math.abs(x) >= 1e5 || (Math.abs(x) < 1e-3 && x !== 0)) ? x.toExponential(digits - 1) : (+x).toPrecision(digits);
  const bytes = (n) => n >= 1 << 30 ? (n / (1 << 30)).toFixed(2) + ' GiB' : n >= 1 << 20 ? (n / (1 << 20)).toFixed(2) + ' MiB'
    : n >= 1024 ? (n / 1024).toFixed(1) + ' KiB' : n + ' B';
  const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  const getJson = async (url) => {
    const r = await fetch(url);
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || r.statusText);
    return body;
  };

  let meta, map, tiles, R, buildId;
  const state = { method: null, layer: 'value', against: null };

  function tileUrl() {
    let q = 'layer=' + state.layer + (state.layer === 'diff' ? '&against=' + state.against : '');
    return '/v1/builds/' + buildId + '/render/' + state.method + '/{z}/{x}/{y}.png?' + q;
  }

  function refreshTiles() {
    $('against-label').hidden = state.layer !== 'diff';
    tiles.setUrl(tileUrl());
    document.body.dataset.layer = state.layer;
    document.body.dataset.method = state.method;
    loadLegend();
  }

  async function loadLegend() {
    const lg = await getJson('/v1/render/legend?layer=' + state.layer);
    let html = '<div><b>' + esc(lg.title) + '</b>' + (lg.unit ? ' <span class="muted small">(' + esc(lg.unit) + ')</span>' : '') + '</div>';
    if (lg.stops) {
      const tick = (t) => lg.scale === 'linear' ? lg.min + t * (lg.max - lg.min)
        : lg.scale === 'log2' ? lg.min * Math.pow(lg.max / lg.min, t) : lg.min * Math.pow(lg.max / lg.min, t);
      html += '<div class="bar" style="background:linear-gradient(to right,' + lg.stops.join(',') + ')"></div>' +
        '<div class="ticks"><span>' + fmt(tick(0), 3) + '</span><span>' + fmt(tick(0.5), 3) + '</span><span>' + fmt(tick(1), 3) +
        '</span></div><div class="small muted">' + (lg.scale === 'linear' ? 'linear' : lg.scale + ' scale') +
        '; transparent: no geometry (lit)</div>';
    }
    const cats = lg.scale === 'categories' ? lg.categories : lg.categories.filter((c) => c.label !== 'stored' && !c.label.startsWith('empty'));
    html += '<div>' + cats.map((c) => '<span class="cat"><span class="swatch" style="background:' + c.colour + '"></span>' + esc(c.label) + '</span>').join('') + '</div>';
    $('legend').innerHTML = html;
  }

  function fillMeta(build) {
    const s = meta.shadow;
    const stats = s.build_stats || {};
    const d = s.light.direction;
    const rows = [
      ['scene', esc(s.scene.name) + ' <span class="muted">(' + s.scene.triangles.toLocaleString() + ' triangles)</span>'],
      ['light direction', d.map((x) => x.toFixed(3)).join(', ') + ' <span class="muted">(sun elevation ' +
        (Math.asin(Math.min(1, Math.max(-1, -d[2]))) * 180 / Math.PI).toFixed(1) + '° if z is up)</span>'],
      ['resolution', R.toLocaleString() + '² texels of ' + fmt(s.light.texel_size) + ' world units'],
      ['tiles', s.tiles_per_side + '² of ' + s.tile_size + '²'],
      ['depth range', fmt(s.light.depth_range) + ' world units'],
      ['default bias', fmt(s.default_bias) + ' world units'],
      ['methods', s.methods.join(', ')],
      ['build time', stats.seconds ? fmt(stats.seconds.total, 3) + ' s' : '–'],
      ['builder', esc(s.builder_version)],
      ['build id', '<code>' + esc(s.build_id) + '</code>'],
    ];
    const contract = build && (build.contract || build.receiver_contract);
    if (contract) rows.splice(5, 0, ['contract', '<code>' + esc(typeof contract === 'string' ? contract : JSON.stringify(contract)) + '</code>']);
    $('meta').innerHTML = rows.map((r) => '<tr><th>' + r[0] + '</th><td>' + r[1] + '</td></tr>').join('');
    const by = stats.bytes_by_method || {};
    const texels = R * R;
    let html = '<tr><th>method</th><th class="num">tiles</th><th class="num">bytes</th><th class="num">bits/texel</th><th class="num">vs raw</th></tr>';
    for (const m of s.methods) {
      const b = by[m];
      html += '<tr data-method="' + m + '"><td>' + m + '</td><td class="num">' + ((s.tiles_by_method || {})[m] ?? '–') +
        '</td><td class="num">' + (b !== undefined ? bytes(b) : '–') + '</td><td class="num">' + (b !== undefined ? fmt(b * 8 / texels, 3) : '–') +
        '</td><td class="num">' + (b !== undefined && by.raw ? fmt(b / by.raw, 3) : '–') + '</td></tr>';
    }
    $('sizes').innerHTML = html;
  }

  // Map position (zoom-0 pixels, CRS.Simple: lng = x, lat = -y) -> texel.
  function texelOf(latlng) {
    return { u: Math.floor(latlng.lng / 256 * R), v: Math.floor(-latlng.lat / 256 * R) };
  }

  async function onClick(e) {
    const t = texelOf(e.latlng);
    if (t.u < 0 || t.v < 0 || t.u >= R || t.v >= R) return;
    let html;
    try {
      const info = await getJson('/v1/texel?u=' + t.u + '&v=' + t.v);
      html = '<div class="texel-popup" data-u="' + info.u + '" data-v="' + info.v + '"><b>texel (' + info.u + ', ' + info.v + ')</b>' +
        ' <span class="muted">tile ' + info.tile.x + ',' + info.tile.y + '</span><table>' +
        '<tr><th>method</th><th>value</th><th>tile bytes</th></tr>' +
        info.methods.map((m) => '<tr data-method="' + m.method + '" data-value="' + (m.value === null ? '' : m.value) + '"><td>' + m.method +
          '</td><td>' + (m.miss ? 'no hit (lit)' : m.value.toPrecision(9)) + '</td><td>' +
          (m.tile_bytes !== undefined ? bytes(m.tile_bytes) : '–') + '</td></tr>').join('') + '</table>' +
        '<div class="muted small">value: normalised depth along the light (0 near plane, 1 far plane)</div></div>';
      if (info.surface_world) {
        ['qx', 'qy', 'qz'].forEach((id, i) => { $(id).value = info.surface_world[i].toPrecision(8); });
      }
    } catch (err) {
      html = '<div class="texel-popup error">' + esc(err.message) + '</div>';
    }
    L.popup().setLatLng(e.latlng).setContent(html).openOn(map);
  }

  async function onQuery(e) {
    e.preventDefault();
    const p = ['qx', 'qy', 'qz'].map((id) => $(id).value.trim());
    let html = '<tr><th>method</th><th>answer</th><th class="num">depth</th></tr>';
    for (const m of meta.shadow.methods) {
      try {
        const a = await getJson('/v1/shadow?x=' + encodeURIComponent(p[0]) + '&y=' + encodeURIComponent(p[1]) + '&z=' +
          encodeURIComponent(p[2]) + '&method=' + m);
        const word = a.lit ? 'lit' : 'shadowed';
        html += '<tr data-method="' + m + '" data-lit="' + a.lit + '"><td>' + m + '</td><td class="' + word + '">' + word +
          (a.outside_map ? ' (outside the map)' : '') + '</td><td class="num">' + fmt(a.depth, 5) + '</td></tr>';
      } catch (err) {
        html += '<tr data-method="' + m + '" data-error="1"><td>' + m + '</td><td colspan="2">' + esc(err.message) + '</td></tr>';
      }
    }
    $('query-result').innerHTML = html;
    $('query-result').dataset.done = String(Date.now());
  }

  function updateOverview() {
    const b = map.getBounds();
    const clamp = (x) => Math.max(0, Math.min(256, x));
    const x0 = clamp(b.getWest()), x1 = clamp(b.getEast()), y0 = clamp(-b.getNorth()), y1 = clamp(-b.getSouth());
    const r = $('overview-rect'), k = 160 / 256;
    r.style.left = x0 * k + 'px'; r.style.top = y0 * k + 'px';
    r.style.width = Math.max(2, (x1 - x0) * k) + 'px'; r.style.height = Math.max(2, (y1 - y0) * k) + 'px';
  }

  async function start() {
    meta = await getJson('/v1/meta');
    const build = await getJson('/v1/build').catch(() => null);
    const s = meta.shadow;
    R = s.resolution;
    buildId = s.build_id;
    $('scene-name').textContent = s.scene.name;
    state.method = s.default_method;
    state.against = s.methods.find((m) => m !== state.method) || state.method;
    for (const [id, value] of [['method', state.method], ['against', state.against]]) {
      $(id).innerHTML = s.methods.map((m) => '<option value="' + m + '">' + m + '</option>').join('');
      $(id).value = value;
    }
    fillMeta(build);
    const maxZoom = Math.max(0, Math.log2(R) - 8 + 3);
    map = L.map('map', { crs: L.CRS.Simple, minZoom: 0, maxZoom: maxZoom, zoomSnap: 0.25, zoomDelta: 0.5, attributionControl: false });
    const bounds = [[-256, 0], [0, 256]];
    tiles = L.tileLayer(tileUrl(), { tileSize: 256, noWrap: true, bounds: bounds, maxNativeZoom: maxZoom, maxZoom: maxZoom,
      keepBuffer: 1 }).addTo(map);
    tiles.on('load', () => { document.body.dataset.tilesLoaded = String(Date.now()); });
    map.fitBounds(bounds);
    map.setMaxBounds([[-320, -64], [64, 320]]);
    map.on('click', onClick);
    map.on('moveend zoomend', updateOverview);
    $('overview-img').src = '/v1/builds/' + buildId + '/render/' + state.method + '/0/0/0.png?layer=depth';
    $('overview').addEventListener('click', (e) => {
      const r = e.currentTarget.getBoundingClientRect();
      map.panTo([-(e.clientY - r.top) / r.height * 256, (e.clientX - r.left) / r.width * 256]);
    });
    updateOverview();
    $('method').addEventListener('change', (e) => { state.method = e.target.value; refreshTiles(); });
    $('layer').addEventListener('change', (e) => { state.layer = e.target.value; refreshTiles(); });
    $('against').addEventListener('change', (e) => { state.against = e.target.value; refreshTiles(); });
    $('query-form').addEventListener('submit', onQuery);
    refreshTiles();
    window.inspector = { map, texelOf, state };  // for the browser test and the console
    document.body.dataset.ready = '1';
  }

  start().catch((err) => {
    document.body.dataset.error = err.message;
    $('panel').insertAdjacentHTML('afterbegin', '<p class="error">Cannot load the build: ' + esc(err.message) + '</p>');
  });
})();
