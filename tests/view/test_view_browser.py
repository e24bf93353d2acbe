"""The viewer in a real browser (Debian's headless Chromium driven by Selenium): the page shows the
data, orbiting and editing the transfer function and an iso-value change the image, and once
refined the displayed image matches the command line's render of the scene the page saves; a new
field gets its own first picture, range boxes show their numbers whole, Save PNG saves the view on
screen, and errors (a stopped server among them) show over the image. Screenshots are kept in the
test-artifacts folder."""
import base64
import json
import os
import re
import shutil
import subprocess
import time

import numpy as np
import pytest
from documents import holds

selenium = pytest.importorskip("selenium", reason="python3-selenium is not installed (see the README's test command)")
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

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


def wait_download(driver, folder, suffix, timeout, what, stem="exabricks"):
    """The file the page downloaded ending in `suffix`, named as Save picture names its files:
    the dataset (`stem`; "exabricks" for the embedded one), the field and the size."""
    def found():
        names = [n for n in os.listdir(folder) if n.endswith(suffix)] if folder.exists() else []
        return folder / names[0] if names else None
    path = wait_for(driver, found, timeout, what)
    assert re.fullmatch(re.escape(stem) + r"-scalar-\d+x\d+" + re.escape(suffix), path.name), path.name
    return path


def wait_refined(driver, after_request=0):
    """The latest frame once refined. Generous: a sanitizer build refines 48 passes of a view the
    data fills in over a minute."""
    def done():
        h = latest(driver)
        return h if h and h["final"] and h["request"] > after_request else None
    return wait_for(driver, done, timeout=240, what="a refined frame")


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

    # Move an opacity point: the middle point of the curve, dragged down.
    editor = browser.find_element(By.ID, "tf-editor")
    points = browser.execute_script("return window.exabricksViewer.doc.layers[0].transfer_function.opacity")
    k = len(points) // 2
    last = points[k]
    width, height = editor.size["width"], editor.size["height"]
    x = 4 + last[0] * (300 - 8)
    y = 4 + (1 - last[1]) * (130 - 12 - 8)
    ActionChains(browser).move_to_element_with_offset(editor, x * width / 300 - width / 2, y * height / 130 - height / 2) \
        .click_and_hold().move_by_offset(0, 25).move_by_offset(0, 25).release().perform()
    moved = browser.execute_script("return window.exabricksViewer.doc.layers[0].transfer_function.opacity")
    assert moved[k][1] < last[1] - 0.1, (last, moved)
    edited = wait_refined(browser, orbited["request"])
    after_tf = canvas_pixels(browser)
    shown = np.maximum(after_tf.max(axis=-1), after_orbit.max(axis=-1)) > 8
    change = np.abs(after_tf.astype(int) - after_orbit.astype(int)).max(axis=-1)
    assert change[shown].mean() > 1.0 and change.max() > 20, "the opacity edit changed nothing"

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
    saved = wait_download(browser, tmp_path / "downloads", ".json", 20, "the saved scene")
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


def transfer_function(driver):
    return driver.execute_script("return window.exabricksViewer.doc.layers[0].transfer_function")


def test_a_new_field_gets_its_own_first_picture(start_viewer, browser, flow_dataset, artifacts):
    # The first view maps 'scalar' logarithmically (--log); 'velocity' has negative values, which a
    # log mapping would hide, so switching to it must choose its own mapping, range and opacity.
    v = start_viewer(str(flow_dataset.resolve()), "--log")
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    assert browser.title.startswith("flow.cells"), browser.title
    assert browser.find_element(By.ID, "dataset-name").text == "flow.cells"
    # The shading choices are the server's vocabulary.
    shading = Select(browser.find_element(By.ID, "shading"))
    assert [o.get_attribute("value") for o in shading.options] == ["analytic", "central", "smooth", "none"]
    assert shading.first_selected_option.get_attribute("value") == "smooth"
    assert transfer_function(browser)["log"] is True
    Select(browser.find_element(By.ID, "field")).select_by_value("velocity")
    wait_for(browser, lambda: transfer_function(browser).get("log") is False, 20, "the new field's mapping")
    wait_refined(browser, first["request"])
    chosen = v.json("GET", "/api/first-picture?field=velocity")["transfer_function"]
    tf = transfer_function(browser)
    assert tf["range"] == pytest.approx(chosen["range"]) and tf["opacity"] == chosen["opacity"], (tf, chosen)
    assert tf["opacity_scale"] == chosen["opacity_scale"]
    assert canvas_pixels(browser).max() > 40, "the velocities do not show"
    note = browser.find_element(By.ID, "field-note")
    assert note.is_displayed() and "velocity" in note.text
    browser.save_screenshot(str(artifacts / "viewer-4-new-field.png"))
    # The range boxes show the whole number (or scientific notation) inside the box.
    for box, value in zip(["range-lo", "range-hi"], tf["range"]):
        text, fits = browser.execute_script(
            "const e = document.getElementById(arguments[0]);"
            "const c = document.createElement('canvas').getContext('2d'); const s = getComputedStyle(e);"
            "c.font = s.fontStyle + ' ' + s.fontWeight + ' ' + s.fontSize + ' ' + s.fontFamily;"
            "const room = e.clientWidth - parseFloat(s.paddingLeft) - parseFloat(s.paddingRight);"
            "return [e.value, e.type === 'text' && c.measureText(e.value).width <= room];", box)
        assert fits, (box, text)
        assert float(text) == pytest.approx(value, rel=1e-4), (box, text, value)
    # A number typed in full is taken exactly, and shown so that it fits.
    hi = browser.find_element(By.ID, "range-hi")
    hi.send_keys(Keys.CONTROL, "a")  # the modifier is released at the end of the call
    hi.send_keys("13222500", Keys.ENTER)
    wait_for(browser, lambda: transfer_function(browser)["range"][1] == 13222500, 10, "the typed range")
    browser.find_element(By.ID, "image").click()  # the box loses the focus
    shown = hi.get_attribute("value")
    assert float(shown) == pytest.approx(13222500, rel=1e-5), shown
    assert browser.execute_script("return window.exabricksViewer.metrics.errors") == []


def test_save_png_saves_the_view_on_screen(start_viewer, cli, browser, tmp_path):
    v = start_viewer("--spp", "48")
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    canvas = browser.find_element(By.ID, "image")
    ActionChains(browser).move_to_element(canvas).click_and_hold().move_by_offset(60, 0).move_by_offset(30, 20) \
        .release().perform()
    # Save at once, while the new view refines: the file is the new view, refined.
    browser.find_element(By.ID, "save-image").click()
    at_click = latest(browser)
    assert not (at_click["final"] and at_click["request"] > first["request"]), "refinement ended before the click"
    saved_png = wait_download(browser, tmp_path / "downloads", ".png", 120, "the saved PNG")
    time.sleep(0.3)
    browser.find_element(By.ID, "save-scene").click()
    saved_scene = wait_download(browser, tmp_path / "downloads", ".json", 20, "the saved scene")
    time.sleep(0.2)
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", "--scene", str(saved_scene), "-o", str(out)], check=True, capture_output=True)
    assert saved_png.read_bytes() == out.read_bytes(), "Save PNG did not save the view on screen"
    assert browser.execute_script("return window.exabricksViewer.metrics.saved")[0] > first["request"]


def test_errors_show_over_the_image_and_a_stopped_server_says_so(start_viewer, browser, artifacts):
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    wait_refined(browser)

    def banner_in_view():
        return browser.execute_script(
            "const b = document.getElementById('banner'); if (b.hidden) return null;"
            "const r = b.getBoundingClientRect(), v = document.getElementById('view').getBoundingClientRect();"
            "return [b.textContent, r.top >= v.top && r.bottom <= v.bottom && r.left >= v.left && r.right <= v.right"
            "  && r.bottom <= window.innerHeight && r.height > 0];")

    # A long field name and note stay inside the side panel (it does not widen or scroll sideways).
    overflow = browser.execute_script(
        "const f = document.getElementById('field'); f.options[0].textContent = 'Y(' + 'C2H4'.repeat(40) + ')';"
        "const n = document.getElementById('field-note'); n.hidden = false; n.textContent = 'x'.repeat(300);"
        "const p = document.getElementById('panel'); return [p.scrollWidth, p.clientWidth, p.offsetWidth];")
    wide = browser.execute_script(
        "const p = document.getElementById('panel').getBoundingClientRect(); const out = [];"
        "for (const e of document.querySelectorAll('#panel *')) { const r = e.getBoundingClientRect();"
        " if (r.right > p.right + 1 && r.width > 0) out.push(e.tagName + '#' + e.id + '.' + e.className + ' ' + r.right); }"
        "return out.slice(0, 8);")
    assert overflow[0] <= overflow[1] and overflow[2] <= 341, (overflow, wide)

    lo = browser.find_element(By.ID, "range-lo")
    lo.clear()
    lo.send_keys("abc" + Keys.ENTER)
    text, placed = wait_for(browser, banner_in_view, 10, "the error banner")
    assert "two numbers" in text and placed, (text, placed)
    browser.save_screenshot(str(artifacts / "viewer-5-error.png"))
    browser.find_element(By.ID, "banner-close").click()
    assert banner_in_view() is None

    assert v.stop() == 0
    text, placed = wait_for(browser, lambda: (banner_in_view() or ["", False])[0] and banner_in_view(), 20,
                            "the stopped-server banner")
    assert "stopped" in text and placed, text
    browser.save_screenshot(str(artifacts / "viewer-6-stopped.png"))


def expect_snapshot_equals_cli(v, cli, tmp_path, saved, name):
    """The view's refined snapshot equals `exabricks render --scene` of the scene the page saved."""
    scene = tmp_path / (name + ".json")
    scene.write_text(json.dumps(saved))
    out = tmp_path / (name + ".png")
    subprocess.run([cli, "render", "--scene", str(scene), "-o", str(out)], check=True, capture_output=True)
    status, png, _ = v.request("GET", "/api/snapshot.png")
    assert status == 200 and png == out.read_bytes()


def test_the_legend_toggles_draw_the_legends_as_the_command_line_does(start_viewer, cli, browser, tmp_path,
                                                                       artifacts):
    """The page's colour-bar and annotation boxes set the scene's legends: the refined canvas shows
    them (it changes where they are drawn) and equals the command line's render of the saved scene,
    legends and all; unticking them gives the picture without."""
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    plain = canvas_pixels(browser)
    for key in ("legends.color_bar", "legends.annotation"):
        box = browser.find_element(By.CSS_SELECTOR, "input[data-setting='%s']" % key)
        assert not box.is_selected()
        box.click()
    shown = wait_refined(browser, first["request"])
    with_legends = canvas_pixels(browser)
    browser.save_screenshot(str(artifacts / "viewer-legends.png"))
    changed = np.abs(with_legends.astype(int) - plain.astype(int)).max(axis=2) > 40
    assert changed.sum() > 200, "the legends did not appear"
    saved = json.loads(v.request("GET", "/api/scene")[1])
    assert saved["legends"]["color_bar"] is True and saved["legends"]["annotation"] is True
    expect_snapshot_equals_cli(v, cli, tmp_path, saved, "legends")
    for key in ("legends.color_bar", "legends.annotation"):
        browser.find_element(By.CSS_SELECTOR, "input[data-setting='%s']" % key).click()
    wait_refined(browser, shown["request"])
    assert np.abs(canvas_pixels(browser).astype(int) - plain.astype(int)).max() <= 2


def test_path_tracing_from_the_page_equals_the_command_line(start_viewer, cli, browser, tmp_path, artifacts):
    """Choosing path tracing in the panel shows its settings (hidden while marching), samples as
    the command line's path tracer (denoised, to its noise target), refines the path-traced picture, and the saved scene rendered by the command line gives the snapshot's
    bytes; an albedo outside [0, 1] is refused in the banner and leaves the scene as it was."""
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    marched = canvas_pixels(browser)
    albedo = browser.find_element(By.CSS_SELECTOR, "input[data-setting='pathtrace.albedo']")
    assert not albedo.is_displayed()
    Select(browser.find_element(By.ID, "integrator")).select_by_value("pathtrace")
    traced = wait_refined(browser, first["request"])
    assert albedo.is_displayed() and float(albedo.get_attribute("value")) == pytest.approx(0.8)
    assert np.abs(canvas_pixels(browser).astype(int) - marched.astype(int)).mean() > 0.5
    # It samples as the command line's path tracer does: to the denoised picture's noise target.
    frame = json.loads(v.request("GET", "/api/scene")[1])["frame"]
    assert frame["noise_target"] == 2 and frame["samples_per_pixel"] == 1024 and frame["denoise"], frame
    denoise = browser.find_element(By.CSS_SELECTOR, "input[data-setting='frame.denoise']")
    assert denoise.is_displayed() and denoise.is_selected()
    assert browser.find_element(By.ID, "spp-out").text == "1024"
    browser.save_screenshot(str(artifacts / "viewer-pathtrace.png"))
    sun = browser.find_element(By.CSS_SELECTOR, "input[data-setting='pathtrace.sun_intensity']")
    sun.clear()
    sun.send_keys("3" + Keys.ENTER)
    wait_refined(browser, traced["request"])
    saved = json.loads(v.request("GET", "/api/scene")[1])
    assert saved["integration"]["integrator"] == "pathtrace" and saved["pathtrace"]["sun_intensity"] == 3
    expect_snapshot_equals_cli(v, cli, tmp_path, saved, "traced")
    albedo.clear()
    albedo.send_keys("2" + Keys.ENTER)
    banner = wait_for(browser, lambda: browser.find_element(By.ID, "banner").is_displayed(), 10, "the banner")
    assert banner and "pathtrace.albedo" in browser.find_element(By.ID, "banner").text
    assert json.loads(v.request("GET", "/api/scene")[1])["pathtrace"]["albedo"] == pytest.approx(0.8)


def test_the_sun_and_the_environment_from_the_page_equal_the_command_line(start_viewer, cli, browser, tmp_path,
                                                                         artifacts):
    """The path tracer's light from the panel: the sun's azimuth and elevation sliders set the way
    its light travels (from the sun at that azimuth around the camera's up and that height), the
    sky-and-ground box sets both colours, a picked environment colour keeps its brightness, and the
    snapshot equals the command line's render of the saved scene. The samples slider reaches 1024."""
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    Select(browser.find_element(By.ID, "integrator")).select_by_value("pathtrace")
    traced = wait_refined(browser, first["request"])

    def slide(element_id, value):
        browser.execute_script("const e = document.getElementById(arguments[0]); e.value = arguments[1];"
                               "e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change'));",
                               element_id, value)

    slide("sun-azimuth", 90)
    slide("sun-elevation", 30)
    browser.find_element(By.ID, "sky-and-ground").click()
    browser.execute_script("const e = document.getElementById('environment-colour'); e.value = '#ff8000';"
                           "e.dispatchEvent(new Event('change'));")
    # Several requests were sent: the last one's refined frame, once no other follows it.
    def last_refined():
        h = latest(browser)
        last = browser.execute_script("return window.exabricksViewer.lastRequest")
        return h if h and h["final"] and h["request"] == last and h["request"] > traced["request"] else None
    wait_for(browser, last_refined, 240, "the last request refined")
    time.sleep(0.5)
    wait_for(browser, last_refined, 240, "the last request refined")
    saved = json.loads(v.request("GET", "/api/scene")[1])
    p = saved["pathtrace"]
    up = np.array(saved["camera"]["up"], float)
    up /= np.linalg.norm(up)
    to_sun = -np.array(p["sun_direction"], float)
    to_sun /= np.linalg.norm(to_sun)
    assert np.degrees(np.arcsin(np.dot(to_sun, up))) == pytest.approx(30, abs=0.01)
    assert p["sky"] and p["ground"] and p["sky"][2] > p["sky"][0]
    # Orange at the brightness the environment had (1): red channel 1, green sRGB 0x80 in linear.
    assert p["environment"][0] == pytest.approx(1) and p["environment"][1] == pytest.approx(0.2158605, abs=1e-6)
    assert p["environment"][2] == pytest.approx(0)
    browser.save_screenshot(str(artifacts / "viewer-lights.png"))
    expect_snapshot_equals_cli(v, cli, tmp_path, saved, "lit")
    assert browser.find_element(By.ID, "spp").get_attribute("max") == "10"
    slide("spp", 10)
    wait_for(browser, lambda: json.loads(v.request("GET", "/api/scene")[1])["frame"]["samples_per_pixel"] == 1024,
             30, "1024 samples per pixel")
    assert browser.find_element(By.ID, "spp-out").text == "1024"
    # The noise target's box (path tracing only): each tile refines to it, the slider its most.
    box = browser.find_element(By.CSS_SELECTOR, "input[data-setting='frame.noise_target']")
    assert box.is_displayed() and box.get_attribute("max") == "255"
    browser.execute_script("const e = arguments[0]; e.value = '3'; e.dispatchEvent(new Event('change'));", box)
    wait_for(browser, lambda: json.loads(v.request("GET", "/api/scene")[1])["frame"]["noise_target"] == 3,
             30, "a noise target of 3/255")


def test_a_loaded_scene_keeps_every_described_key(start_viewer, browser, scene_example, tmp_path, artifacts):
    """A scene loaded through the page (the example of every structured key) renders, and the scene
    in effect (what the page sent) still holds every key at its value, those the page does not edit
    included; a scene naming a mesh file is refused in the banner and leaves the view as it was."""
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    uploadable, example = scene_example
    load = browser.find_element(By.ID, "load-scene")
    (tmp_path / "example.json").write_text(json.dumps(example))
    load.send_keys(str(tmp_path / "example.json"))
    wait_for(browser, lambda: browser.find_element(By.ID, "banner").is_displayed(), 10, "the banner")
    assert "reads no file" in browser.find_element(By.ID, "banner").text
    assert "camera_path" not in json.loads(v.request("GET", "/api/scene")[1])
    browser.execute_script("window.exabricksViewer.metrics.errors.length = 0")
    (tmp_path / "uploadable.json").write_text(json.dumps(uploadable))
    load.send_keys(str(tmp_path / "uploadable.json"))
    loaded = wait_refined(browser, first["request"])
    browser.save_screenshot(str(artifacts / "viewer-example-scene.png"))
    assert browser.execute_script("return window.exabricksViewer.lastRequest") == loaded["request"]
    holds(json.loads(v.request("GET", "/api/scene")[1]), uploadable, "the scene in effect")
    # The panel shows what it edits of it; the corners show its background (sRGB 32, 64, 128).
    assert Select(browser.find_element(By.ID, "colormap")).first_selected_option.get_attribute("value") == "inferno"
    assert Select(browser.find_element(By.ID, "iso-colormap")).first_selected_option.get_attribute("value") == "custom"
    fov = browser.find_element(By.ID, "fov")
    assert not fov.is_enabled() and float(fov.get_attribute("value")) == 35  # an orthographic camera
    corner = canvas_pixels(browser)[1, 1].astype(int)
    assert np.abs(corner - [32, 64, 128]).max() <= 6, corner
    # An edit of one key leaves the others as they were.
    browser.find_element(By.CSS_SELECTOR, "input[data-setting='legends.color_bar']").click()
    wait_refined(browser, loaded["request"])
    edited = json.loads(v.request("GET", "/api/scene")[1])
    assert edited["legends"]["color_bar"] is True
    holds(edited, uploadable, "the scene after an edit")
    assert browser.execute_script("return window.exabricksViewer.metrics.errors") == []


def test_structured_controls_take_their_limits_and_choices_from_the_description(start_viewer, browser):
    """The colour-map choosers offer the choices the scene's description gives the colormap key of
    a transfer function, and the field of view takes its limits and help from camera.fov's: a value
    outside (0, 180) is refused in the banner, one inside sets the camera's."""
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    structure = v.json("GET", "/api/structure")
    assert browser.execute_script("return window.exabricksViewer.structure") == structure
    colormap = next(e for e in structure if e.get("object") == "transfer_function" and e["key"] == "colormap")
    for chooser in ("colormap", "iso-colormap"):
        options = Select(browser.find_element(By.ID, chooser)).options
        assert [o.get_attribute("value") for o in options] == colormap["choices"], chooser
    described = next(e for e in structure if e.get("object") == "camera" and e["key"] == "fov")
    assert described["min_exclusive"] and described["max_exclusive"]
    fov = browser.find_element(By.ID, "fov")
    assert float(fov.get_attribute("min")) == described["min"] and float(fov.get_attribute("max")) == described["max"]
    assert fov.get_attribute("title") == described["help"] and fov.is_enabled()
    camera = browser.execute_script("return window.exabricksViewer.doc.camera")
    assert float(fov.get_attribute("value")) == pytest.approx(camera["fov"])
    for wrong in ("180", "0"):
        fov.clear()
        fov.send_keys(wrong + Keys.ENTER)
        wait_for(browser, lambda: browser.find_element(By.ID, "banner").is_displayed(), 10, "the banner")
        assert "camera.fov must be in (0, 180)" in browser.find_element(By.ID, "banner").text
        assert browser.execute_script("return window.exabricksViewer.doc.camera.fov") == camera["fov"]
        browser.find_element(By.ID, "banner-close").click()
    browser.execute_script("window.exabricksViewer.metrics.errors.length = 0")
    fov.clear()
    fov.send_keys("25" + Keys.ENTER)
    wait_refined(browser, first["request"])
    assert json.loads(v.request("GET", "/api/scene")[1])["camera"]["fov"] == 25
    browser.find_element(By.ID, "reset-view").click()
    wait_for(browser, lambda: float(fov.get_attribute("value")) == pytest.approx(camera["fov"]), 10, "the reset")
    assert browser.execute_script("return window.exabricksViewer.metrics.errors") == []
