/* Sets #report-status to "ok" when every section rendered without error. */
// Builds the report from the JSON embedded in #report-data.
'use strict';
(function () {
  const DATA = JSON.parse(document.getElementById('report-data').textContent);
  const root = document.getElementById('report');
  const summary = DATA.summary || {};
  const images = DATA.images || [];
  const names = images.map((image) => image.name);
  const views = [];

  function section(id, title, lead) {
    const node = el('section', { class: 'card', id }, main);
    el('h2', {}, node, title);
    if (lead) el('p', { class: 'lead' }, node, lead);
    return node;
  }
  function missing(parent, text) { el('p', { class: 'missing' }, parent, text); }
  // Runs one section; a failure is reported (and fails the browser test) without hiding the
  // other sections.
  function guarded(name, body) {
    try {
      body();
    } catch (error) {
      console.error('section ' + name + ': ' + (error && error.stack ? error.stack : error));
    }
  }

  // Header and navigation.
  const header = el('header', { class: 'top' }, root);
  const headerWrap = el('div', { class: 'wrap' }, header);
  el('h1', {}, headerWrap, DATA.title || 'Parallax reconstruction report');
  const registered = summary.images_registered ?? images.filter((image) => image.registered).length;
  const total = summary.images_total ?? images.length;
  el('p', {}, headerWrap, `Incremental Structure-from-Motion · ${registered} of ${total} images registered` +
     (DATA.scene ? ` · ${fmt(DATA.scene.num_points_total)} 3D points` : ''));
  const nav = el('div', { class: 'wrap' }, el('nav', {}, root));
  const main = el('div', { class: 'wrap' }, el('main', {}, root));
  const sections = [['overview', 'Overview'], ['scene', '3D model'], ['features', 'Features'],
                    ['matching', 'Matching'], ['reprojection', 'Reprojection error']];
  if (DATA.evaluation) sections.push(['evaluation', 'Ground truth']);
  sections.push(['timings', 'Timings'], ['images', 'Images']);
  for (const [id, title] of sections) el('a', { href: '#' + id }, nav, title);

  guarded('overview', () => {
    const node = section('overview', 'Overview');
    const cards = el('div', { class: 'cards' }, node);
    const stat = (value, label) => {
      const card = el('div', { class: 'stat' }, cards);
      el('div', { class: 'value' }, card, value);
      el('div', { class: 'label' }, card, label);
    };
    stat(`${registered} / ${total}`, 'images registered');
    stat(fmt(summary.points3D ?? (DATA.scene ? DATA.scene.num_points_total : null)), '3D points');
    stat(fmt(summary.mean_track_length, 2), 'mean track length (images per point)');
    stat(summary.mean_reprojection_error_px === undefined ? '–' : fmt(summary.mean_reprojection_error_px, 3) + ' px',
         'mean reprojection error');
    const timings = summary.timings_s || {};
    stat(timings.total === undefined ? '–' : fmt(timings.total, 1) + ' s', 'total time');
    stat(fmt((summary.models || []).length || null), 'models (connected components)');
    if (DATA.evaluation) {
      const e = DATA.evaluation;
      stat(fmt(e.rotation_error_deg.median, 3) + '°', 'median rotation error vs. ground truth');
      stat(fmt(100 * e.center_error_relative.median, 2) + ' %', 'median camera-centre error (of scene scale)');
    }
    const histogram = summary.track_length_histogram || [];
    if (histogram.length > 0) {
      el('h3', {}, node, 'Track lengths');
      el('p', { class: 'note' }, node,
         'Points by the number of images that observe them: the longer the tracks, the more ' +
         'images each point ties together.');
      barChart(node, { labels: histogram.map((bin) => String(bin.length)), height: 220,
                       xTitle: 'images per point', yTitle: 'points',
                       series: [{ name: 'points', color: '#4c78a8',
                                  values: histogram.map((bin) => bin.points) }] });
    }
  });

  guarded('scene', () => {
    const node = section('scene', '3D model',
      'Coloured sparse point cloud, every registered camera as a frustum (cyan = first image of ' +
      'the sequence, magenta = last) and the trajectory through the camera centres (orange). ' +
      'Drag to orbit, right-drag or shift-drag to pan, scroll to zoom, double-click to reset.');
    if (!DATA.scene) { missing(node, 'No reconstruction.'); return; }
    const prepared = prepareScene(DATA.scene);
    const controls = el('div', { class: 'controls' }, node);
    el('span', {}, controls, `${fmt(prepared.numPoints)} points shown` +
       (DATA.scene.num_points > 0 && DATA.scene.num_points < DATA.scene.num_points_total
           ? ` (of ${fmt(DATA.scene.num_points_total)})` : '') +
       ` · ${DATA.scene.cameras.length} cameras`);
    const box = el('div', { class: 'viewer main' }, node);
    const canvas = el('canvas', { id: 'scene-canvas' }, box);
    const view = new SceneView(canvas, prepared, { yaw: -30, pitch: 25, interactive: true });
    views.push(view);
    el('div', { class: 'tag' }, box, view.gl ? 'WebGL' : 'canvas 2D');
    const toggle = (label, key) => {
      const wrap = el('label', {}, controls);
      const input = el('input', { type: 'checkbox', checked: '' }, wrap);
      wrap.appendChild(document.createTextNode(' ' + label));
      input.addEventListener('change', () => {
        for (const v of views) { v[key] = input.checked; v.render(); }
      });
    };
    toggle('cameras', 'showCameras');
    toggle('trajectory', 'showTrajectory');
    const sizeWrap = el('label', {}, controls, 'point size ');
    const slider = el('input', { type: 'range', min: '0.5', max: '4', step: '0.25', value: '1' }, sizeWrap);
    slider.addEventListener('input', () => { view.pointScale = Number(slider.value); view.render(); });
    const reset = el('button', {}, controls, 'reset view');
    reset.addEventListener('click', () => { view.reset(); view.render(); });
    if (DATA.scene.points_radius > 0) {
      const zoom = el('button', {}, controls, 'zoom to points');
      zoom.addEventListener('click', () => {
        view.target = [0, 0, 0];
        view.distance = DATA.scene.points_radius / Math.sin(Math.PI / 8);
        view.render();
      });
    }

    el('h3', {}, node, 'Fixed views');
    el('p', { class: 'note' }, node,
       '"Front" looks along the mean viewing direction of the cameras (for a ring of cameras, ' +
       'along the first camera\'s), with "up" opposite the images\' down direction; the other ' +
       'views turn about the up axis in steps of 90°.');
    const grid = el('div', { class: 'grid4' }, node);
    for (const [label, yaw] of [['front', 0], ['right', -90], ['back', 180], ['left', 90]]) {
      const small = el('div', { class: 'viewer small' }, grid);
      const smallCanvas = el('canvas', { 'data-view': label }, small);
      el('div', { class: 'tag' }, small, label);
      views.push(new SceneView(smallCanvas, prepared, { yaw, pitch: 20, small: true }));
    }
    for (const v of views) v.render();
    // Reading pixels back stalls the GPU: only the browser test (?selftest) asks for it.
    if (/selftest/.test(location.search)) {
      document.getElementById('report-pixels').textContent = String(view.countDrawnPixels());
    }
    window.addEventListener('resize', () => { for (const v of views) v.render(); });
  });

  guarded('features', () => {
    const node = section('features', 'Features',
      'SIFT keypoints drawn on two frames (circles have the keypoint\'s scale) and the number ' +
      'of keypoints detected in each image.');
    const frames = DATA.frames || { list: [], keypoint_frames: [] };
    if (frames.keypoint_frames.length === 0) { missing(node, 'No images.'); return; }
    const grid = el('div', { class: 'grid2' }, node);
    for (const index of frames.keypoint_frames) {
      const frame = frames.list[index];
      const figure = el('figure', {}, grid);
      frameSvg(figure, frame, frame.keypoints || []);
      const drawn = (frame.keypoints || []).length / 3;
      el('figcaption', {}, figure, `${names[frame.image]} — ${fmt(frame.num_keypoints || 0)} keypoints` +
         (drawn < (frame.num_keypoints || 0) ? ` (${fmt(drawn)} drawn)` : ''));
    }
    el('h3', {}, node, 'Keypoints per image');
    const counts = images.map((image) => Math.max(image.keypoints, 0));
    barChart(node, { labels: names, series: [{ name: 'keypoints', values: counts,
      colors: images.map((image) => (image.registered ? PALETTE.blue : PALETTE.grey)) }],
      yTitle: 'keypoints', digits: 0,
      tips: (i) => (images[i].registered ? 'registered' : 'not registered') });
    const mean = counts.reduce((a, b) => a + b, 0) / Math.max(counts.length, 1);
    el('p', { class: 'note' }, node, `Mean ${fmt(mean, 0)} keypoints per image; grey bars are images that were not registered.`);
  });

  guarded('matching', () => {
    const node = section('matching', 'Matching',
      'Putative matches come from descriptor matching; inliers are the matches that survive ' +
      'the RANSAC geometric verification (essential, fundamental or homography matrix).');
    if (!DATA.has_database) { missing(node, 'No database: match statistics are not available.'); return; }
    const n = images.length;
    const putative = Array.from({ length: n }, () => new Array(n).fill(0));
    const inliers = Array.from({ length: n }, () => new Array(n).fill(0));
    for (const [i, j, p, q] of DATA.pairs) {
      putative[i][j] = putative[j][i] = p;
      inliers[i][j] = inliers[j][i] = q;
    }
    const best = DATA.best_pair;
    el('h3', {}, node, 'Correspondences of the best pair');
    if (best) {
      const f1 = DATA.frames.list[best.frame1], f2 = DATA.frames.list[best.frame2];
      const figure = el('figure', {}, node);
      pairSvg(figure, f1, f2, best.lines);
      el('figcaption', {}, figure, `${names[f1.image]} ↔ ${names[f2.image]}: ${fmt(best.num_inliers)} ` +
         `inlier matches (${fmt(best.lines.length / 4)} drawn)`);
    } else {
      missing(node, 'No verified pair.');
    }
    const heat = el('div', { class: 'heat' }, node);
    heatmap(heat, { title: 'Putative matches per pair', labels: names, matrix: putative, unit: 'putative matches' });
    heatmap(heat, { title: 'Inlier matches per pair', labels: names, matrix: inliers, unit: 'inlier matches' });
    el('p', { class: 'note' }, node, 'Rows and columns are images in database order (hover for names and counts).');

    if (n > 1) {
      el('h3', {}, node, `Matches of the first image (${names[0]}) with every other image`);
      const others = names.slice(1);
      barChart(node, { labels: others, series: [
        { name: 'putative', values: putative[0].slice(1), color: '#b9c9ee' },
        { name: 'inliers', values: inliers[0].slice(1), color: PALETTE.blue }],
        yTitle: 'matches', digits: 0 });
    }

    el('h3', {}, node, 'Average matches per image pair, before and after RANSAC');
    const avgPutative = [], avgInliers = [];
    for (let i = 0; i < n; ++i) {
      let pairs = 0, sumP = 0, sumQ = 0;
      for (let j = 0; j < n; ++j) {
        if (j === i || putative[i][j] === 0) continue;
        ++pairs; sumP += putative[i][j]; sumQ += inliers[i][j];
      }
      avgPutative.push(pairs ? sumP / pairs : 0);
      avgInliers.push(pairs ? sumQ / pairs : 0);
    }
    barChart(node, { labels: names, series: [
      { name: 'putative (before RANSAC)', values: avgPutative, color: PALETTE.orange },
      { name: 'inliers (after RANSAC)', values: avgInliers, color: PALETTE.green }],
      yTitle: 'matches per pair', digits: 1 });
    el('p', { class: 'note' }, node, 'Averages over the pairs of each image that have at least one putative match.');
  });

  guarded('reprojection', () => {
    const node = section('reprojection', 'Reprojection error per image',
      'Mean distance in pixels between each observed keypoint and the projection of its 3D ' +
      'point, when the image was registered (before bundle adjustment) and in the final model.');
    const before = images.map((image) => image.error_before_ba);
    const after = images.map((image) => image.error_after_ba);
    if (after.every((v) => v === null) && before.every((v) => v === null)) {
      missing(node, 'No registered image.');
      return;
    }
    const series = [];
    if (before.some((v) => v !== null)) series.push({ name: 'before bundle adjustment', values: before, color: PALETTE.orange });
    series.push({ name: 'after bundle adjustment', values: after, color: PALETTE.blue });
    barChart(node, { labels: names, series, yTitle: 'pixels', digits: 3, legend: true });
    if (series.length === 1) el('p', { class: 'note' }, node, 'summary.json has no errors before bundle adjustment.');
  });

  if (DATA.evaluation) guarded('evaluation', () => {
    const e = DATA.evaluation;
    const node = section('evaluation', 'Comparison with ground truth',
      'The model is aligned to the ground-truth cameras by a similarity fitted robustly (RANSAC) ' +
      'to the camera centres; errors are measured after that alignment. Relative centre errors ' +
      'are fractions of the scene scale: the mean distance of the ground-truth centres from ' +
      'their centroid.');
    const table = el('table', { class: 'data kv' }, node);
    const row = (label, value) => { const tr = el('tr', {}, table); el('td', {}, tr, label); el('td', {}, tr, value); };
    row('images registered / in ground truth', `${e.images_registered_in_gt} / ${e.images_gt}`);
    row('alignment inliers', e.alignment.success ? `${e.alignment.num_inliers}` : 'alignment failed');
    row('scene scale (ground-truth units)', fmt(e.gt_scene_scale, 4));
    const triple = (s, k, d) => `${fmt(k * s.median, d)} / ${fmt(k * s.mean, d)} / ${fmt(k * s.max, d)}`;
    row('rotation error median / mean / max (°)', triple(e.rotation_error_deg, 1, 3));
    row('centre error median / mean / max (GT units)', triple(e.center_error, 1, 4));
    row('centre error median / mean / max (% of scale)', triple(e.center_error_relative, 100, 2));
    el('h3', {}, node, 'Accuracy (fraction of all ground-truth images below each threshold)');
    el('p', { class: 'note' }, node, 'Unregistered images count as failures. AUC is the mean over ' +
       'images of max(0, 1 − error / threshold): the normalised area under the cumulative error ' +
       'curve up to the threshold (1 when every image is exact).');
    const grid = el('div', { class: 'grid2' }, node);
    const accuracy = el('table', { class: 'data' }, grid);
    const head = el('tr', {}, el('thead', {}, accuracy));
    for (const title of ['threshold', 'fraction below', 'AUC']) el('th', {}, head, title);
    const labels = [], fraction = [], auc = [];
    const addRow = (label, p) => {
      labels.push(label); fraction.push(p.fraction); auc.push(p.auc);
      const tr = el('tr', {}, accuracy);
      el('td', {}, tr, label); el('td', {}, tr, fmt(p.fraction, 3)); el('td', {}, tr, fmt(p.auc, 3));
    };
    for (const p of e.rotation_accuracy) addRow(`rotation ≤ ${p.threshold}°`, p);
    for (const p of e.center_accuracy_relative) addRow(`centre ≤ ${+(100 * p.threshold).toPrecision(4)} %`, p);
    barChart(el('div', {}, grid), { labels, shortLabels: labels, width: 620, height: 240, digits: 3,
      yTitle: 'fraction', series: [{ name: 'fraction below threshold', values: fraction, color: PALETTE.green },
                                   { name: 'AUC', values: auc, color: PALETTE.purple }] });
    const evaluated = e.images.filter((image) => image.rotation_error_deg !== undefined);
    if (evaluated.length) {
      el('h3', {}, node, 'Errors per image');
      const errors = el('div', { class: 'grid2' }, node);
      barChart(el('div', {}, errors), { labels: evaluated.map((i) => i.name), width: 620, height: 260, digits: 3,
        yTitle: 'rotation error (°)', series: [{ name: 'rotation error (°)', values: evaluated.map((i) => i.rotation_error_deg),
        colors: evaluated.map((i) => (i.alignment_inlier ? PALETTE.blue : PALETTE.red)) }] });
      barChart(el('div', {}, errors), { labels: evaluated.map((i) => i.name), width: 620, height: 260, digits: 3,
        yTitle: 'centre error (% of scale)', series: [{ name: 'centre error (%)', values: evaluated.map((i) => 100 * i.center_error_relative),
        colors: evaluated.map((i) => (i.alignment_inlier ? PALETTE.orange : PALETTE.red)) }] });
      if (evaluated.some((i) => !i.alignment_inlier)) {
        el('p', { class: 'note' }, node, 'Red bars: cameras rejected as outliers by the alignment.');
      }
    }
  });

  guarded('timings', () => {
    const node = section('timings', 'Stage timings', 'Wall-clock time of each stage of the pipeline.');
    const timings = summary.timings_s || {};
    const order = ['features', 'matching', 'verification', 'mapping', 'bundle_adjustment', 'export'];
    const keys = Object.keys(timings).filter((k) => k !== 'total' && typeof timings[k] === 'number');
    keys.sort((a, b) => (order.indexOf(a) + 1 || 99) - (order.indexOf(b) + 1 || 99));
    if (keys.length === 0) { missing(node, 'summary.json has no timings.'); return; }
    const totalTime = typeof timings.total === 'number' ? timings.total : keys.reduce((s, k) => s + timings[k], 0);
    const colors = [PALETTE.blue, PALETTE.orange, PALETTE.green, PALETTE.purple, PALETTE.red, PALETTE.grey];
    horizontalBars(node, { labels: keys, values: keys.map((k) => timings[k]), unit: 's', digits: 2,
                           total: totalTime, colors: keys.map((k, i) => colors[i % colors.length]) });
    el('p', { class: 'note' }, node, `Total ${fmt(totalTime, 2)} s.`);
  });

  guarded('images', () => {
    const node = section('images', 'Images', 'Per-image summary (red rows: not registered, with the reason).');
    const scroll = el('div', { class: 'scroll' }, node);
    const table = el('table', { class: 'data' }, scroll);
    const head = el('tr', {}, el('thead', {}, table));
    for (const title of ['#', 'image', 'registered', 'keypoints', 'observations', 'error before BA (px)',
                         'error after BA (px)', 'note']) {
      el('th', ['image', 'note'].includes(title) ? { class: 'left' } : {}, head, title);
    }
    const body = el('tbody', {}, table);
    images.forEach((image, i) => {
      const tr = el('tr', image.registered ? {} : { class: 'unregistered' }, body);
      el('td', {}, tr, String(i + 1));
      el('td', { class: 'left' }, tr, image.name);
      const cell = el('td', {}, tr);
      el('span', { class: 'pill ' + (image.registered ? 'yes' : 'no') }, cell, image.registered ? 'yes' : 'no');
      el('td', {}, tr, image.keypoints >= 0 ? fmt(image.keypoints) : '–');
      el('td', {}, tr, image.observations >= 0 ? fmt(image.observations) : '–');
      el('td', {}, tr, fmt(image.error_before_ba, 3));
      el('td', {}, tr, fmt(image.error_after_ba, 3));
      el('td', { class: 'left' }, tr, image.reason || '');
    });
  });

  el('footer', {}, root, 'Generated by Parallax. Self-contained: no network access needed.');
  installTooltips();
  if (window.reportErrors.length === 0) document.getElementById('report-status').textContent = 'ok';
})();
