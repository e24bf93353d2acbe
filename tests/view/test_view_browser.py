"""The viewer in a real browser (Debian's headless Chromium driven by Selenium): the page shows the
data, orbiting and editing the transfer function and an iso-value change the image, and once
refined the displayed image matches the command line's render of the scene the page saves.
Screenshots are kept in the test-artifacts folder."""
import base64
import json
import os
import shutil
import subprocess
import time

import numpy as np
import pytest

selenium = pytest.importorskip("selenium", reason="python3-selenium is not installed (see the README's test command)")
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
SIZE = 192


@pytest.fixture
def browser(tmp_path):
    if not (os.path.exists(CHROMIUM) and os.path.exists(DRIVER)):
        pytest.skip("chromium and chromium-driver are not installed (see the README's test command)")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for a in ["--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1280,900",
              "--disable-dev-shm-usage"]:
        options.add_argument(a)
    options.add_experimental_option("prefs", {"download.default_directory": str(tmp_path / "downloads"),
                                              "download.prompt_for_download": False})
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    driver.set_script_timeout(60)
    yield driver
    driver.quit()


def latest(driver):
    return driver.execute_script("return window.exabricksViewer.latest")


def wait_for(driver, predicate, timeout=90, what="the condition"):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError("timed out waiting for %s; errors on the page: %s" % (
        what, driver.execute_script("return window.exabricksViewer && window.exabricksViewer.metrics.errors")))


def wait_refined(driver, after_request=0):
    def done():
        h = latest(driver)
        return h if h and h["final"] and h["request"] > after_request else None
    return wait_for(driver, done, what="a refined frame")


def wait_new_frame(driver, after_sequence):
    return wait_for(driver, lambda: (latest(driver) or {}).get("sequence", 0) > after_sequence, what="a new frame")


def canvas_pixels(driver):
    """The canvas as an (H, W, 3) uint8 array (what the page shows, at the frame's resolution)."""
    data = driver.execute_script(
        "const c = document.getElementById('image');"
        "const d = c.getContext('2d').getImageData(0, 0, c.width, c.height);"
        "let s = ''; const b = d.data; for (let i = 0; i < b.length; i += 8192)"
        "  s += String.fromCharCode.apply(null, b.subarray(i, i + 8192));"
        "return [c.width, c.height, btoa(s)];")
    w, h, b64 = data
    return np.frombuffer(base64.b64decode(b64), np.uint8).reshape(h, w, 4)[:, :, :3]


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), "<f4" if scale < 0 else ">f4").reshape(h, w, 3)
    return data[::-1]


def srgb8(linear):
    c = np.clip(linear, 0, 1)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.rint(s * 255).astype(np.int32)


def test_orbit_edit_and_refine_match_the_command_line(start_viewer, cli, browser, tmp_path, artifacts):
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    assert (first["width"], first["height"]) == (SIZE, SIZE)
    before = canvas_pixels(browser)
    assert before.max() > 40, "the first picture is black"
    browser.save_screenshot(str(artifacts / "viewer-1-first.png"))

    # Orbit: drag across the image.
    canvas = browser.find_element(By.ID, "image")
    camera = browser.execute_script("return JSON.stringify(window.exabricksViewer.doc.camera)")
    seq = latest(browser)["sequence"]
    ActionChains(browser).move_to_element(canvas).click_and_hold().move_by_offset(40, 0).move_by_offset(40, 10) \
        .release().perform()
    wait_new_frame(browser, seq)
    orbited = wait_refined(browser, first["request"])
    assert browser.execute_script("return JSON.stringify(window.exabricksViewer.doc.camera)") != camera
    after_orbit = canvas_pixels(browser)
    assert np.abs(after_orbit.astype(int) - before.astype(int)).mean() > 1.0, "orbiting did not change the image"
    browser.save_screenshot(str(artifacts / "viewer-2-orbited.png"))

    # Move an opacity point: the last point of the curve, dragged down.
    editor = browser.find_element(By.ID, "tf-editor")
    points = browser.execute_script("return window.exabricksViewer.doc.layers[0].transfer_function.opacity")
    last = points[-1]
    width, height = editor.size["width"], editor.size["height"]
    x = 4 + last[0] * (300 - 8)
    y = 4 + (1 - last[1]) * (130 - 12 - 8)
    ActionChains(browser).move_to_element_with_offset(editor, x * width / 300 - width / 2, y * height / 130 - height / 2) \
        .click_and_hold().move_by_offset(0, 25).move_by_offset(0, 25).release().perform()
    moved = browser.execute_script("return window.exabricksViewer.doc.layers[0].transfer_function.opacity")
    assert moved[-1][1] < last[1] - 0.1, (last, moved)
    edited = wait_refined(browser, orbited["request"])
    after_tf = canvas_pixels(browser)
    assert np.abs(after_tf.astype(int) - after_orbit.astype(int)).mean() > 0.5, "the opacity edit changed nothing"

    # Add an iso-surface and drag its value.
    browser.find_element(By.ID, "iso-add").click()
    added = wait_refined(browser, edited["request"])
    slider = wait_for(browser, lambda: browser.find_elements(By.CSS_SELECTOR, ".iso-value-slider"), what="iso slider")[0]
    value = browser.execute_script("return window.exabricksViewer.doc.iso.values[0]")
    ActionChains(browser).move_to_element(slider).click_and_hold().move_by_offset(-slider.size["width"] // 5, 0) \
        .release().perform()
    new_value = browser.execute_script("return window.exabricksViewer.doc.iso.values[0]")
    assert new_value < value
    with_iso = canvas_pixels(browser)
    refined = wait_refined(browser, added["request"])
    with_iso = canvas_pixels(browser)
    assert np.abs(with_iso.astype(int) - after_tf.astype(int)).mean() > 0.5, "the iso-surface changed nothing"
    browser.save_screenshot(str(artifacts / "viewer-3-edited.png"))
    assert refined["passes"] == refined["target_passes"]

    # Save the scene the way the page does (the button downloads it) and render it on the
    # command line: the displayed image matches within JPEG's error.
    browser.find_element(By.ID, "save-scene").click()
    saved = tmp_path / "downloads" / "scene.json"
    wait_for(browser, saved.exists, 20, "the saved scene")
    time.sleep(0.2)
    doc = json.loads(saved.read_text())
    assert doc["iso"]["values"] == pytest.approx([new_value], rel=1e-5)
    out_png, out_pfm = tmp_path / "cli.png", tmp_path / "cli.pfm"
    subprocess.run([cli, "render", "--scene", str(saved), "-o", str(out_png), "--float", str(out_pfm)], check=True,
                   capture_output=True)
    shown = canvas_pixels(browser).astype(np.int32)
    reference = srgb8(read_pfm(out_pfm))
    assert shown.shape == reference.shape
    diff = np.abs(shown - reference)
    assert diff.mean() < 1.5 and np.percentile(diff, 99) < 12, (diff.mean(), np.percentile(diff, 99))
    # The lossless snapshot the page saves as PNG equals the command line's PNG exactly.
    status, png, _ = v.request("GET", "/api/snapshot.png")
    assert status == 200 and png == out_png.read_bytes()
    errors = browser.execute_script("return window.exabricksViewer.metrics.errors")
    assert errors == []
