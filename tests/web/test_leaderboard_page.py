"""The leaderboard site in a real browser: Debian's Chromium, headless, driven by selenium through the system
chromedriver (nothing is downloaded). scripts/setup.sh installs both; where they are missing this test skips and
says so."""

from __future__ import annotations

import shutil

import pytest
from board_data import SUITE, entry, synthetic_info, write

from gendex.eval.leaderboard import build_site
from gendex.eval.suite import load_suite

CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")


@pytest.fixture
def browser():
    if not (CHROMIUM and DRIVER):
        pytest.skip("Debian's chromium and chromium-driver are not installed (scripts/setup.sh installs them as root)")
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (the dev extra has it)")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync"):
        opts.add_argument(arg)
    opts.binary_location = CHROMIUM
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    yield driver
    driver.quit()


def test_the_board_loads_sorts_and_opens_a_per_task_breakdown(tmp_path, browser):
    from selenium.webdriver.common.by import By

    root = tmp_path / "board"
    tasks = load_suite(SUITE).tasks
    for name, k in (("weak", 2), ("strong", 9), ("middle", 5)):
        write(root, name, entry(name.title(), synthetic_info({t: k for t in tasks})))
    build_site(tmp_path / "site", root)
    browser.get((tmp_path / "site" / "index.html").as_uri())
    browser.find_element(By.LINK_TEXT, SUITE).click()
    assert browser.title == f"GenDex leaderboard: {SUITE}"
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors

    def methods():
        return [r.find_element(By.TAG_NAME, "a").text for r in browser.find_elements(By.CSS_SELECTOR, "tr.entry")]

    assert methods() == ["Strong", "Middle", "Weak"]  # best first as built
    success = browser.find_element(By.CSS_SELECTOR, 'th[data-key="success"]')
    success.click()
    assert methods() == ["Weak", "Middle", "Strong"] and "sorted-asc" in success.get_attribute("class")
    success.click()
    assert methods() == ["Strong", "Middle", "Weak"]
    browser.find_element(By.CSS_SELECTOR, 'th[data-key="method"]').click()
    assert methods() == ["Middle", "Strong", "Weak"]
    row = browser.find_elements(By.CSS_SELECTOR, "tr.entry")[1]  # Strong
    detail = browser.find_element(By.ID, row.get_attribute("data-detail"))
    assert not detail.is_displayed()
    row.find_element(By.CSS_SELECTOR, "button.toggle").click()
    assert detail.is_displayed() and "GenDex/OpenCabinet-v1" in detail.text and "9/10" in detail.text
    assert [e for e in browser.get_log("browser") if e["level"] == "SEVERE"] == []


def test_the_per_skill_columns_sort_in_the_browser(tmp_path, browser):
    from selenium.webdriver.common.by import By

    root = tmp_path / "board"
    groups = {"GenDex/PutAppleBowl-v1": "put_in", "GenDex/PickUpBottle-v2": "lift",
              "GenDex/OpenCabinet-v1": "open_door"}
    # overall order Even > Lifter > Putter, but per skill each leads its own column
    for name, rates in (("lifter", (1, 10, 1)), ("putter", (9, 1, 1)), ("even", (6, 6, 6))):
        info = synthetic_info(dict(zip(groups, rates, strict=True)), groups=groups)
        write(root, name, entry(name.title(), info))
    build_site(tmp_path / "site", root)
    browser.get((tmp_path / "site" / f"{SUITE}.html").as_uri())

    def methods():
        return [r.find_element(By.TAG_NAME, "a").text for r in browser.find_elements(By.CSS_SELECTOR, "tr.entry")]

    assert methods() == ["Even", "Lifter", "Putter"]
    for skill, best in (("lift", "Lifter"), ("put_in", "Putter"), ("open_door", "Even")):
        th = browser.find_element(By.CSS_SELECTOR, f'th[data-key="skill-{skill}"]')
        th.click()  # ascending
        th.click()  # descending: the best at this skill first
        assert methods()[0] == best and "sorted-desc" in th.get_attribute("class"), (skill, methods())
    assert [e for e in browser.get_log("browser") if e["level"] == "SEVERE"] == []


def test_the_committed_board_sorts_by_every_skill_without_console_errors(tmp_path, browser):
    """The real board (leaderboard/, every suite with results): each suite page loads without a console error, and
    clicking a skill's column orders the methods by that skill's success, descending on the second click."""
    from selenium.webdriver.common.by import By

    from gendex.eval.leaderboard import LEADERBOARD_DIR, suites_with_results

    build_site(tmp_path / "site", LEADERBOARD_DIR)
    names = suites_with_results(LEADERBOARD_DIR)
    assert "gendex-skills-v2" in names
    sorted_skills = 0
    for name in names:
        browser.get((tmp_path / "site" / f"{name}.html").as_uri())
        assert browser.title == f"GenDex leaderboard: {name}"
        heads = browser.find_elements(By.CSS_SELECTOR, 'th[data-key^="skill-"]')
        col = {th.get_attribute("data-key"): i for i, th in
               enumerate(browser.find_elements(By.CSS_SELECTOR, "table.board th[data-key]"))} if heads else {}
        for key in [th.get_attribute("data-key") for th in heads]:
            th = browser.find_element(By.CSS_SELECTOR, f'th[data-key="{key}"]')
            th.click()
            th.click()
            rows = browser.find_elements(By.CSS_SELECTOR, "tr.entry")
            values = [float(r.find_elements(By.TAG_NAME, "td")[col[key]].get_attribute("data-value") or "nan")
                      for r in rows]
            present = [v for v in values if v == v]
            assert present == sorted(present, reverse=True), (name, key, values)
            assert "sorted-desc" in th.get_attribute("class")
            sorted_skills += 1
        assert [e for e in browser.get_log("browser") if e["level"] == "SEVERE"] == [], name
    assert sorted_skills >= 13  # gendex-skills-v2 alone has a column for each of its skills
