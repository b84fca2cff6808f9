# The GUI tests drive a real Chromium. Debian's apt package is one. Where apt
# only offers a snap stub (Ubuntu 24.04, where snaps do not run in containers),
# Playwright's own Chromium build is fetched instead; that download comes from
# Playwright's server, so this one case needs internet once.
if [ "$FTT_SETUP_MODE" = test ]; then
    if chromium_path=$(ftt_working_chromium); then
        ftt_log "browser for the GUI tests: $chromium_path"
    else
        playwright_version=$("$FTT_PY" -m playwright --version)
        if ftt_stamp_ok playwright-chromium "$playwright_version"; then
            ftt_log "browser for the GUI tests: Playwright's Chromium"
        else
            ftt_log "no Chromium from apt that starts; installing Playwright's Chromium"
            "$FTT_PY" -m playwright install --with-deps chromium ||
                ftt_die "could not install a Chromium for the GUI tests (no internet?)"
            ftt_stamp_write playwright-chromium "$playwright_version"
        fi
    fi
fi
