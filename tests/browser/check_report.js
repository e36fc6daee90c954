// Open a report.html in headless Chromium and check what a reader sees: no console error
// or page error, every image loaded (decoded, not broken), no request leaves the file,
// and hovering a method's image shows the reference in its place.
//
//   node check_report.js REPORT.html CHROMIUM [SCREENSHOT.png]
//
// Prints one line "ok: N images" or "FAIL: ..." and exits non-zero on failure.
const { chromium } = require("playwright-core");
const fs = require("fs");
const os = require("os");
const path = require("path");
const url = require("url");

async function main() {
  const [report, exe, shot] = process.argv.slice(2);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "kalos-chromium-"));
  // a new profile (--user-data-dir) of its own
  const browser = await chromium.launchPersistentContext(profile, {
    executablePath: exe,
    headless: true,
    viewport: { width: 1400, height: 1000 },
    args: [
      "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync",
    ],
  });
  const problems = [];
  try {
    const page = await browser.newPage();
    page.on("console", (m) => { if (m.type() === "error") problems.push(`console error: ${m.text()}`); });
    page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
    page.on("request", (r) => {
      if (!r.url().startsWith("data:") && !r.url().startsWith("file:")) problems.push(`network request: ${r.url()}`);
    });
    await page.goto(url.pathToFileURL(path.resolve(report)).href, { waitUntil: "load" });
    const imgs = await page.$$eval("img", (all) => all.map((i) => ({
      alt: i.alt, complete: i.complete, w: i.naturalWidth, h: i.naturalHeight,
    })));
    if (imgs.length === 0) problems.push("no images");
    for (const i of imgs) {
      if (!i.complete || i.w === 0 || i.h === 0) problems.push(`image not loaded: ${i.alt}`);
    }
    // hover flipping: a method's image shows the reference while the mouse is over it
    const flip = await page.$("img.flip");
    if (!flip) {
      problems.push("no image to flip");
    } else {
      const own = await flip.getAttribute("src");
      const refId = await flip.getAttribute("data-ref");
      const ref = await page.$eval(`#${refId}`, (r) => r.src);
      await flip.hover();
      const over = await flip.evaluate((i) => i.src);
      await page.mouse.move(0, 0);
      const back = await flip.evaluate((i) => i.src);
      if (over !== ref) problems.push("hovering does not show the reference");
      if (back !== own) problems.push("leaving does not restore the image");
    }
    if (shot) await page.screenshot({ path: shot, fullPage: true });
    console.log(problems.length ? `FAIL: ${problems.join("; ")}` : `ok: ${imgs.length} images`);
  } finally {
    await browser.close();
    fs.rmSync(profile, { recursive: true, force: true });
  }
  process.exit(problems.length ? 1 : 0);
}

main().catch((e) => { console.log(`FAIL: ${e.message.split("\n")[0]}`); process.exit(1); });
