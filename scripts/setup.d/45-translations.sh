# The German catalogues: locale/<lang>/LC_MESSAGES/*.po compiled to .mo with GNU
# gettext's msgfmt (what `manage.py compilemessages` runs). The .mo files are
# built here, not committed: they follow from the .po files, are binary and
# would conflict on every merge. A .mo newer than its .po is left alone.
ftt_apt_ensure "gettext"
while IFS= read -r -d '' po; do
    mo=${po%.po}.mo
    if [ ! -f "$mo" ] || [ "$po" -nt "$mo" ]; then
        ftt_log "msgfmt ${po#"$FTT_ROOT"/}"
        msgfmt --check-format -o "$mo" "$po"
    fi
done < <(find "$FTT_ROOT/locale" -name '*.po' -print0 2>/dev/null)
