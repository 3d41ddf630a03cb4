// weft view in a real browser (issue 44, docs/view.md): Debian's chromium,
// driven by playwright-core, against `weft view` on a small knit.
//   node tests/browser/view_test.mjs WEFT_BINARY SOURCE_DIR WORK_DIR
// Checks: the page shows an image that is not blank; a drag changes it; a
// colour change moves the yarn's mean colour that way; Save writes a scene
// whose `weft render` at the same spp matches the view (SSIM >= 0.9); a
// malformed message and a path out of the page are refused while the page
// keeps refining. Exits 77 (skipped) without chromium or playwright-core.
import { execFileSync } from 'node:child_process';
import { mkdirSync, rmSync, readFileSync, copyFileSync } from 'node:fs';
import path from 'node:path';
import { launchBrowser, startView, waitForFrame, imageStats } from './view_lib.mjs';

const [weft, source, work] = process.argv.slice(2);
if (!weft || !source || !work) {
  console.error('usage: node view_test.mjs WEFT_BINARY SOURCE_DIR WORK_DIR');
  process.exit(2);
}
const browserOrSkip = await launchBrowser();
if (!browserOrSkip) process.exit(77);
const browser = browserOrSkip;

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}

rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const sceneDir = path.join(work, 'knit');
execFileSync(weft, ['scene', 'knit', '--model', path.join(source, 'models/fleece-colour.json'),
  '--width', '96', '--height', '96', '--spp', '4', '--out', sceneDir], { stdio: 'ignore' });
const out = path.join(work, 'saved');
const view = await startView(weft, [path.join(sceneDir, 'scene.json'), '--out', out, '--threads', '2']);
let page;
try {
  page = await browser.newPage({ viewport: { width: 1100, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(view.url);

  // 1. An image that is not blank.
  let frame = await waitForFrame(page, 'neural', { spp: 1 });
  let stats = await imageStats(page, 'neural');
  check(stats.mean > 0.02 && stats.std > 0.01, `first image is not blank (mean ${stats.mean.toFixed(3)}, std ${stats.std.toFixed(3)})`);

  // 2. A drag turns the camera: a new image that differs.
  const img = await page.locator('#neural').boundingBox();
  const before = await imageStats(page, 'neural', true);
  await page.mouse.move(img.x + img.width / 2, img.y + img.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 6; i++) await page.mouse.move(img.x + img.width / 2 + 15 * i, img.y + img.height / 2 + 4 * i);
  await page.mouse.up();
  const generation = await page.evaluate(() => fetch('/api/stats').then((r) => r.json()).then((s) => s.generation));
  frame = await waitForFrame(page, 'neural', { spp: 4, generation });
  const after = await imageStats(page, 'neural', true);
  let diff = 0;
  for (let i = 0; i < before.pixels.length; i++) diff += Math.abs(before.pixels[i] - after.pixels[i]);
  diff /= before.pixels.length * 255;
  check(diff > 0.01, `a drag changes the image (mean absolute change ${diff.toFixed(4)})`);

  // 3. The colour picker: red, then blue; the yarn's red / blue follows.
  async function colourTo(hex) {
    await page.locator('[data-role=appearance]').first().evaluate((input, value) => {
      input.value = value;
      input.dispatchEvent(new Event('input', { bubbles: true }));
    }, hex);
    await page.waitForTimeout(300);
    const g = await page.evaluate(() => fetch('/api/stats').then((r) => r.json()).then((s) => s.generation));
    await waitForFrame(page, 'neural', { spp: 4, generation: g });
    return (await imageStats(page, 'neural', true)).pixels;
  }
  const redPixels = await colourTo('#c03020');
  const bluePixels = await colourTo('#2030c0');
  // The yarn's pixels: those the colour changed (nothing else did).
  const red = { r: 0, b: 0 }, blue = { r: 0, b: 0 };
  let yarnPixels = 0;
  for (let i = 0; i < redPixels.length; i += 4) {
    const changed = Math.max(...[0, 1, 2].map((c) => Math.abs(redPixels[i + c] - bluePixels[i + c])));
    if (changed < 8) continue;
    yarnPixels++;
    red.r += redPixels[i]; red.b += redPixels[i + 2];
    blue.r += bluePixels[i]; blue.b += bluePixels[i + 2];
  }
  check(yarnPixels > 500, `the colour changed ${yarnPixels} of 9216 pixels (the yarn's)`);
  check(red.r / red.b > 1.3 * (blue.r / blue.b),
    `a colour change moves the yarn colour (red/blue ${(red.r / red.b).toFixed(3)} for red, ${(blue.r / blue.b).toFixed(3)} for blue)`);

  // 4. Save, then weft render the saved scene at its spp: the same image.
  await page.click('#save');
  await page.waitForSelector('#saved[data-scene]', { timeout: 30000 });
  const savedName = await page.locator('#saved').getAttribute('data-scene');
  const saved = path.join(out, savedName);
  const scene = JSON.parse(readFileSync(saved, 'utf8'));
  const rendered = path.join(work, 'rendered.exr');
  execFileSync(weft, ['render', saved, '--out', rendered, '--threads', '2'], { stdio: 'ignore' });
  execFileSync(weft, ['compare', saved.replace(/\.json$/, '.exr'), rendered,
    '--json', path.join(work, 'compare.json')], { stdio: 'ignore' });
  const compare = JSON.parse(readFileSync(path.join(work, 'compare.json'), 'utf8'));
  check(compare.ssim >= 0.9, `weft render of the saved scene (${scene.render.spp} spp) matches the view: SSIM ${compare.ssim.toFixed(4)}`);

  // 5. Hostile messages: refused, and the view keeps serving.
  const hostile = await page.evaluate(async () => {
    const edit = await fetch('/api/edit', { method: 'POST', body: '{"yarns": [{"index": 0, "model": "../../../etc/passwd"}]}' });
    const malformed = await fetch('/api/edit', { method: 'POST', body: '{"camera": [' });
    const traversal = await fetch('/..%2f..%2f..%2fetc%2fpasswd');
    return { edit: edit.status, editBody: await edit.text(), malformed: malformed.status, traversal: traversal.status };
  });
  check(hostile.edit === 400 && hostile.editBody.includes('not one of the models'), `a model path from the page is refused (${hostile.edit})`);
  check(hostile.malformed === 400, `a malformed message is refused (${hostile.malformed})`);
  check(hostile.traversal === 404, `a path out of the page is refused (${hostile.traversal})`);
  const fov = await page.locator('#fov');
  await fov.evaluate((input) => { input.value = '25'; input.dispatchEvent(new Event('input', { bubbles: true })); });
  await page.waitForTimeout(300);
  const g2 = await page.evaluate(() => fetch('/api/stats').then((r) => r.json()).then((s) => s.generation));
  frame = await waitForFrame(page, 'neural', { spp: 1, generation: g2 });
  check(Number(frame.generation) >= g2, 'still serving: an edit after them gives a new image');
  check(errors.length === 0, `no script errors in the page (${errors.join('; ')})`);
  await page.screenshot({ path: path.join(work, 'view.png') });
  if (process.env.WEFT_VIEW_SCREENSHOT) copyFileSync(path.join(work, 'view.png'), process.env.WEFT_VIEW_SCREENSHOT);
} catch (e) {
  console.log('FAIL ' + (e && e.stack ? e.stack : e));
  failures++;
} finally {
  await browser.close();
  await view.stop();
}
console.log(failures ? `${failures} check(s) failed` : 'all checks passed');
process.exit(failures ? 1 : 0);
