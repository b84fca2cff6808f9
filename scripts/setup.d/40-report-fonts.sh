# Fonts for the PDF report: DejaVu covers Latin, Greek, Cyrillic, Hebrew and
# Arabic, WenQuanYi Micro Hei (1.6 MB, far smaller than Noto CJK) covers
# Chinese, Japanese and Korean, and Noto Color Emoji covers emoji, so names and
# notes in any of those render instead of as boxes.
ftt_apt_ensure "fonts-dejavu-core" "fonts-wqy-microhei|fonts-noto-cjk" "fonts-noto-color-emoji"
