// Real-browser test of the inspector page (issue 17): Debian's chromium, headless, driven by
// playwright-core against a running `shadowtiles serve`. Usage:
//   node inspector_test.mjs BASE_URL ARTIFACT_DIR POINTS_JSON [DOCS_SCREENSHOT]
// POINTS_JSON: `shadowtiles query --ground-truth ... --sample N --json` output (raw method).
// Exit 0 when every check passes; each failed check prints a line and the exit code is 1.
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const [base, artifacts, pointsFile, docsShot] = process.argv.slice(2);
fs.mkdirSync(artifacts, { recursive: true });
let failures = 0;
const check = (ok, what) => {
  console.log((ok ? 'ok   ' : 'FAIL ') + what);
  if (!ok) failures++;
};
const api = async (url) => (await fetch(base + url)).json();

const meta = await api('/v1/meta');
const R = meta.shadow.resolution;
const methods = meta.shadow.methods;

// Pixel statistics of a PNG (a screenshot), computed by the browser itself: share of pixels that
// differ from the most common colour, and a coarse 16x16 signature to compare two pictures.
async function pictureStats(page, png) {
  return page.evaluate(async (b64) => {
    const img = new Image();
    img.src = 'data:image/png;base64,' + b64;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width; c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const counts = new Map();
    for (let i = 0; i < d.length; i += 4) {
      const k = (d[i] << 16) | (d[i + 1] << 8) | d[i + 2];
      counts.set(k, (counts.get(k) || 0) + 1);
    }
    let top = 0;
    for (const v of counts.values()) top = Math.max(top, v);
    const sig = [];
    for (let by = 0; by < 16; by++) for (let bx = 0; bx < 16; bx++) {
      let s = 0, n = 0;
      for (let y = Math.floor(by * c.height / 16); y < Math.floor((by + 1) * c.height / 16); y += 2)
        for (let x = Math.floor(bx * c.width / 16); x < Math.floor((bx + 1) * c.width / 16); x += 2) {
          const i = (y * c.width + x) * 4; s += d[i] + d[i + 1] + d[i + 2]; n++;
        }
      sig.push(n ? s / n : 0);
    }
    return { nonBackground: 1 - top / (d.length / 4), colours: counts.size, sig };
  }, png.toString('base64'));
}
const sigDistance = (a, b) => a.sig.reduce((s, x, i) => s + Math.abs(x - b.sig[i]), 0) / a.sig.length;

async function tilesSettled(page) {
  await page.waitForLoadState('networkidle');
  await page.waitForFunction(() => {
    const imgs = [...document.querySelectorAll('#map img.leaflet-tile')];
    return imgs.length > 0 && imgs.every((i) => i.complete && i.naturalWidth > 0);
  }, null, { timeout: 20000 });
}

function boxesApart(a, b) {
  return a.x + a.width <= b.x + 0.5 || b.x + b.width <= a.x + 0.5 || a.y + a.height <= b.y + 0.5 || b.y + b.height <= a.y + 0.5;
}

async function layoutCheck(page, label, width, height) {
  const map = await page.locator('#map').boundingBox();
  const panel = await page.locator('#panel').boundingBox();
  check(map && map.width >= 0.5 * width && map.height >= 200 && map.x >= 0 && map.y >= 0 &&
        map.x + map.width <= width + 0.5 && map.y + map.height <= height + 0.5, `${label}: map inside the viewport (${JSON.stringify(map)})`);
  check(panel && panel.width >= 300 && panel.height >= 150 && panel.y < height - 100,
        `${label}: panel visible (${JSON.stringify(panel)})`);
  check(map && panel && boxesApart(map, panel), `${label}: map and panel do not overlap`);
  const legend = await page.locator('#legend').boundingBox();
  check(legend && legend.height > 20, `${label}: legend drawn`);
}

const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'shadowtiles-chromium-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: '/usr/bin/chromium',
  headless: true,
  viewport: { width: 1280, height: 720 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
try {
  const page = context.pages()[0] || await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  const external = [];
  const renders = [];
  page.on('request', (r) => {
    if (!r.url().startsWith(base) && !r.url().startsWith('data:')) external.push(r.url());
    if (r.url().includes('/render/') && r.url().includes('.png')) renders.push(r.url());
  });

  await page.goto(base + '/', { waitUntil: 'load' });
  await page.waitForSelector('body[data-ready="1"]', { timeout: 20000 });
  await tilesSettled(page);
  check(await page.evaluate(() => typeof L !== 'undefined' && L.version !== undefined), 'Leaflet loaded from the server');

  // 1. Tiles load: the map is not blank, and the coverage layer looks different.
  const valueShot = await page.locator('#map').screenshot();
  fs.writeFileSync(path.join(artifacts, 'map-value.png'), valueShot);
  const valueStats = await pictureStats(page, valueShot);
  check(valueStats.nonBackground > 0.05 && valueStats.colours > 50,
        `value layer not blank (${(100 * valueStats.nonBackground).toFixed(1)}% non-background, ${valueStats.colours} colours)`);
  await page.selectOption('#layer', 'coverage');
  await tilesSettled(page);
  const coverageShot = await page.locator('#map').screenshot();
  fs.writeFileSync(path.join(artifacts, 'map-coverage.png'), coverageShot);
  const coverageStats = await pictureStats(page, coverageShot);
  check(coverageStats.nonBackground > 0.05, 'coverage layer not blank');
  check(sigDistance(valueStats, coverageStats) > 8, `value and coverage differ (mean block difference ${sigDistance(valueStats, coverageStats).toFixed(1)})`);
  await page.selectOption('#layer', 'value');
  await tilesSettled(page);

  // 2. Switching method reloads the tiles from that method.
  const other = methods.find((m) => m !== meta.shadow.default_method);
  const before = renders.length;
  await page.selectOption('#method', other);
  await tilesSettled(page);
  const fresh = renders.slice(before);
  check(fresh.length > 0 && fresh.every((u) => u.includes('/render/' + other + '/')), `switching to ${other} requested ${fresh.length} ${other} tiles`);
  const srcs = await page.evaluate(() => [...document.querySelectorAll('#map img.leaflet-tile')].map((i) => i.src));
  check(srcs.length > 0 && srcs.every((s) => s.includes('/render/' + other + '/')), 'every tile shown is of the new method');

  // 3. A click's popup shows the API's values for that texel.
  const points = JSON.parse(fs.readFileSync(pointsFile, 'utf8'));
  const hit = points.find((p) => !p.outside_map && !p.empty_tile && p.value < 1);
  const target = await page.evaluate(([u, v, R]) => {
    const p = inspector.map.latLngToContainerPoint([-(v / R) * 256, (u / R) * 256]);
    const box = document.getElementById('map').getBoundingClientRect();
    return { x: box.left + p.x, y: box.top + p.y };
  }, [hit.u, hit.v, R]);
  await page.mouse.click(target.x, target.y);
  await page.waitForSelector('.texel-popup', { timeout: 10000 });
  const popup = await page.evaluate(() => {
    const el = document.querySelector('.texel-popup');
    return { u: +el.dataset.u, v: +el.dataset.v,
             rows: [...el.querySelectorAll('tr[data-method]')].map((r) => ({ method: r.dataset.method, value: r.dataset.value })) };
  });
  // The texel under the click, from Leaflet's own projection (independent of the page's code).
  const clicked = await page.evaluate(([x, y, R]) => {
    const box = document.getElementById('map').getBoundingClientRect();
    const ll = inspector.map.containerPointToLatLng([x - box.left, y - box.top]);
    return { u: Math.floor(ll.lng / 256 * R), v: Math.floor(-ll.lat / 256 * R) };
  }, [target.x, target.y, R]);
  check(popup.u === clicked.u && popup.v === clicked.v, `popup texel (${popup.u}, ${popup.v}) is the clicked one (${clicked.u}, ${clicked.v})`);
  check(Math.abs(popup.u - hit.u) <= 2 && Math.abs(popup.v - hit.v) <= 2, `clicked near the aimed texel (${hit.u.toFixed(1)}, ${hit.v.toFixed(1)})`);
  const truth = await api(`/v1/texel?u=${popup.u}&v=${popup.v}`);
  check(popup.rows.length === methods.length, `popup lists ${popup.rows.length} of ${methods.length} methods`);
  for (const m of truth.methods) {
    const row = popup.rows.find((r) => r.method === m.method);
    const shown = row && row.value !== '' ? Number(row.value) : null;
    check(row && shown === m.value, `popup ${m.method} value ${row && row.value} equals the API's ${m.value}`);
  }
  const rawRow = truth.methods.find((m) => m.method === 'raw');
  if (rawRow && rawRow.value !== null) {
    // The API's raw value is the stored first hit, which the query CLI reported for this texel.
    const texelOfHit = Math.floor(hit.u) === popup.u && Math.floor(hit.v) === popup.v;
    if (texelOfHit) check(rawRow.value === hit.value, `raw value equals the query's texel value ${hit.value}`);
  }

  // 4. The form's answers equal /v1/shadow's for a ground-truth-shadowed and a ground-truth-lit point.
  const shadowed = points.find((p) => !p.outside_map && p.ground_truth_lit === false && p.lit === false);
  const lit = points.find((p) => !p.outside_map && p.ground_truth_lit === true && p.lit === true && !p.empty_tile);
  check(shadowed && lit, 'the sample has a shadowed and a lit ground-truth point');
  for (const [label, p] of [['shadowed', shadowed], ['lit', lit]]) {
    if (!p) continue;
    await page.fill('#qx', String(p.point[0]));
    await page.fill('#qy', String(p.point[1]));
    await page.fill('#qz', String(p.point[2]));
    const stamp = await page.evaluate(() => document.getElementById('query-result').dataset.done || '');
    await page.click('#query-form button');
    await page.waitForFunction((s) => (document.getElementById('query-result').dataset.done || '') !== s, stamp, { timeout: 10000 });
    const answers = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#query-result tr[data-method]')]
      .map((r) => [r.dataset.method, r.dataset.lit])));
    for (const m of methods) {
      const a = await api(`/v1/shadow?x=${p.point[0]}&y=${p.point[1]}&z=${p.point[2]}&method=${m}`);
      check(answers[m] === String(a.lit), `${label} point, ${m}: form says lit=${answers[m]}, /v1/shadow ${a.lit}`);
    }
    check(answers.raw === (label === 'lit' ? '1' : '0'), `${label} point: raw answer agrees with ground truth`);
  }

  // 5. Layout at desktop and phone sizes, with screenshots.
  await page.evaluate(() => inspector.map.closePopup());
  await page.selectOption('#method', meta.shadow.default_method);
  await tilesSettled(page);
  await layoutCheck(page, '1280x720', 1280, 720);
  await page.screenshot({ path: path.join(artifacts, 'inspector-1280x720.png') });
  await page.setViewportSize({ width: 375, height: 667 });
  await page.reload({ waitUntil: 'load' });
  await page.waitForSelector('body[data-ready="1"]', { timeout: 20000 });
  await tilesSettled(page);
  await layoutCheck(page, '375x667', 375, 667);
  const phoneMap = await pictureStats(page, await page.locator('#map').screenshot());
  check(phoneMap.nonBackground > 0.05, 'phone: map not blank');
  await page.screenshot({ path: path.join(artifacts, 'inspector-375x667.png') });

  if (docsShot) {
    await page.setViewportSize({ width: 1024, height: 576 });
    await page.reload({ waitUntil: 'load' });
    await page.waitForSelector('body[data-ready="1"]', { timeout: 20000 });
    await page.selectOption('#layer', 'depth');
    await tilesSettled(page);
    await page.screenshot({ path: docsShot });
  }
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
  check(external.length === 0, `nothing loaded from outside the server (${external.slice(0, 3).join(', ')})`);
} finally {
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
console.log(failures ? `${failures} check(s) failed` : 'all checks passed');
process.exit(failures ? 1 : 0);
