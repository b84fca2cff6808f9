# The GUI's JavaScript tooling (ESLint, axe-core) from package-lock.json, for the
# test run only; skipped while the lock file is unchanged since the last install.
if [ "$FTT_SETUP_MODE" = test ]; then
    npm_lock_hash=$(sha256sum "$FTT_ROOT/package-lock.json" | cut -d' ' -f1)
    if [ -d "$FTT_ROOT/node_modules" ] && ftt_stamp_ok npm-test "$npm_lock_hash"; then
        ftt_log "npm packages: already installed"
    else
        ftt_log "npm ci (ESLint, axe-core)"
        (cd "$FTT_ROOT" && npm ci --no-audit --no-fund --loglevel=error)
        ftt_stamp_write npm-test "$npm_lock_hash"
    fi
fi
