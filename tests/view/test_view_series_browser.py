"""The viewer over a time series in a real browser (headless Chromium driven by Selenium): the step
slider and play, the step's name, time and cycle, the image after stepping equals the command
line's render of the scene the page saves, the movie button's download, the help overlay and the
field chooser's units. Screenshots are kept in the test-artifacts folder."""
import json
import shutil
import subprocess
import time

import numpy as np
import pytest

from test_view_browser import (SIZE, browser, canvas_pixels, latest, read_pfm, srgb8, wait_download,  # noqa: F401
                               wait_for, wait_refined)

from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402


def series(driver):
    return driver.execute_script("const s = window.exabricksViewer.series.info; return s && JSON.parse(JSON.stringify(s))")


def set_slider(driver, value):
    driver.execute_script(
        "const s = document.getElementById('step'); s.value = arguments[0];"
        "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));", value)


def test_slider_and_play_step_through_the_series_as_the_command_line_renders(
        start_viewer, cli, browser, series_dataset, tmp_path, artifacts):  # noqa: F811
    v = start_viewer(series_dataset)
    browser.get(v.url + "&size=%d" % SIZE)
    first = wait_refined(browser)
    assert browser.find_element(By.ID, "series-section").is_displayed()
    assert browser.find_element(By.ID, "step-name").text == "s_0000.cells"
    assert browser.find_element(By.ID, "step-out").text == "1/3"
    assert "cycle" in browser.find_element(By.ID, "step-cycle").text
    before = canvas_pixels(browser)

    set_slider(browser, 2)
    wait_for(browser, lambda: (series(browser) or {}).get("current") == 2, 30, "step 2")
    stepped = wait_refined(browser, first["request"])
    assert browser.find_element(By.ID, "step-name").text == "s_0002.cells"
    assert browser.find_element(By.ID, "step-out").text == "3/3"
    shown = canvas_pixels(browser)
    assert np.abs(shown.astype(int) - before.astype(int)).mean() > 0.5, "stepping did not change the image"
    browser.save_screenshot(str(artifacts / "viewer-series-1-step2.png"))

    # The scene the page saves names the step; the command line renders what the page shows.
    browser.find_element(By.ID, "save-scene").click()
    saved = wait_download(browser, tmp_path / "downloads", ".json", 20, "the saved scene", stem="s_0002")
    time.sleep(0.2)
    doc = json.loads(saved.read_text())
    assert doc["input"].endswith("s_0002.cells")
    out_png, out_pfm = tmp_path / "cli.png", tmp_path / "cli.pfm"
    subprocess.run([cli, "render", "--scene", str(saved), "-o", str(out_png), "--float", str(out_pfm)], check=True,
                   capture_output=True)
    reference = srgb8(read_pfm(out_pfm))
    assert shown.shape == reference.shape
    diff = np.abs(shown.astype(np.int32) - reference)
    assert diff.mean() < 1.5 and np.percentile(diff, 99) < 12, (diff.mean(), np.percentile(diff, 99))
    assert stepped["request"] > first["request"]

    # Play: the steps advance (wrapping to the first), and pause stops them.
    browser.find_element(By.ID, "play").click()
    assert browser.find_element(By.ID, "play").text == "Pause"
    wait_for(browser, lambda: (series(browser) or {}).get("current") == 0, 60, "play to reach step 0")
    wait_for(browser, lambda: (series(browser) or {}).get("current") == 1, 60, "play to reach step 1")
    browser.find_element(By.ID, "play").click()
    assert browser.find_element(By.ID, "play").text == "Play"
    time.sleep(0.5)
    now = series(browser)["current"]
    time.sleep(2)
    assert series(browser)["current"] == now, "pause did not stop the steps"
    assert browser.execute_script("return window.exabricksViewer.metrics.errors") == []


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_the_movie_button_renders_the_series_and_offers_the_file(
        start_viewer, browser, series_dataset, tmp_path, artifacts):  # noqa: F811
    v = start_viewer(series_dataset, "--spp", "1")
    browser.get(v.url + "&size=96")
    wait_refined(browser)
    browser.find_element(By.ID, "make-movie").click()
    link = browser.find_element(By.ID, "movie-download")
    wait_for(browser, link.is_displayed, 120, "the download link")
    assert "3 frames" in browser.find_element(By.ID, "movie-text").text
    browser.save_screenshot(str(artifacts / "viewer-series-2-movie.png"))
    link.click()
    movie = tmp_path / "downloads" / "exabricks.mp4"
    wait_for(browser, lambda: movie.exists() and movie.stat().st_size > 0, 30, "the downloaded movie")
    time.sleep(0.3)
    assert movie.read_bytes()[4:8] == b"ftyp"
    assert browser.execute_script("return window.exabricksViewer.metrics.errors") == []


def test_the_help_overlay_opens_with_the_button_and_the_key(start_viewer, browser, artifacts):  # noqa: F811
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    wait_refined(browser)
    help_box = browser.find_element(By.ID, "help")
    assert not help_box.is_displayed()
    browser.find_element(By.ID, "help-button").click()
    assert help_box.is_displayed()
    text = help_box.text
    for words in ["orbit", "pan", "zoom", "reset the view", "Escape", "Time series", "Volume", "Clipping",
                  "make a movie"]:
        assert words in text, words
    browser.save_screenshot(str(artifacts / "viewer-help.png"))
    ActionChains(browser).send_keys("\ue00c").perform()  # Escape
    assert not help_box.is_displayed()
    browser.find_element(By.ID, "image").click()
    ActionChains(browser).send_keys("?").perform()
    assert help_box.is_displayed()
    ActionChains(browser).send_keys("\ue00c").perform()
    assert not help_box.is_displayed()


def test_the_field_chooser_shows_units(start_viewer, browser, tmp_path):  # noqa: F811
    v = start_viewer()
    browser.get(v.url + "&size=%d" % SIZE)
    wait_refined(browser)
    info = v.info()
    options = browser.execute_script(
        "return [...document.getElementById('field').options].map((o) => [o.value, o.textContent])")
    expected = [[f["name"], "%s [%s]" % (f["name"], f["units"]) if f["units"] else f["name"]] for f in info["fields"]]
    assert options == expected
    # A field with units is named "name [units]" (the data's own units, from /api/info).
    browser.execute_script(
        "const v = window.exabricksViewer; v.info.fields[0].units = 'g/cm^3'; v.syncControls();")
    first = browser.execute_script("return document.getElementById('field').options[0].textContent")
    assert first == "%s [g/cm^3]" % info["fields"][0]["name"]
