#!/usr/bin/env node
// Wall-clock load time of kinsynth's browser report in Chromium, measured by the browser's own
// clock through the DevTools protocol (playwright-core). Not used by the tests.
//
// usage: npm install playwright-core && node view_load_time.js PAGE.html [RUNS] [CHROMIUM]
//
// Per run it prints the browser's start, and the time from navigation until the page has decoded
// its data, built the scene and drawn its first frame (`window.kinsynthView.loadMs`, the page's
// `performance.now()` when it is ready), then the time until two more frames are on screen.
const { chromium } = require('playwright-core');
const path = require('path');

(async () => {
  const page = path.resolve(process.argv[2]);
  const runs = Number(process.argv[3] || 3);
  const executablePath = process.argv[4] || '/usr/bin/chromium';
  for (let i = 0; i < runs; i++) {
    const t0 = Date.now();
    const browser = await chromium.launch({
      executablePath,
      args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox'],
    });
    const t1 = Date.now();
    const p = await browser.newPage({ viewport: { width: 1280, height: 800 } });
    const t2 = Date.now();
    await p.goto('file://' + page);
    await p.waitForFunction(() => window.kinsynthView && window.kinsynthView.ready, null,
      { timeout: 60000 });
    const ready = await p.evaluate(() => window.kinsynthView.loadMs);
    await p.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    const t3 = Date.now();
    console.log(`${path.basename(page)}: browser start ${t1 - t0} ms, ready ${ready.toFixed(0)} ms ` +
      `after navigation (first frame drawn), two more frames at ${t3 - t2} ms`);
    await browser.close();
  }
})().catch((e) => { console.error(e); process.exit(1); });
