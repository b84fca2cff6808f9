"""Django settings for FTT.

Everything that differs between a laptop on the test field and a production
server comes from ``FTT_*`` environment variables; README.md lists them.
"""

from pathlib import Path

from ftt_site import native_libs, sqlite_shim

sqlite_shim.install()
native_libs.preload()

import dj_database_url  # noqa: E402
from django.core.management.utils import get_random_secret_key  # noqa: E402

from ftt_site.env import env_bool, env_int, env_list, env_str  # noqa: E402

BASE_DIR = Path(__file__).resolve().parent.parent
DATA_DIR = Path(env_str("FTT_DATA_DIR", str(BASE_DIR / "data")))
DATA_DIR.mkdir(parents=True, exist_ok=True)

DEBUG = env_bool("FTT_DEBUG", False)


def _secret_key() -> str:
    key = env_str("FTT_SECRET_KEY")
    if key:
        return key
    # An embedded install has nobody to invent a key, so we make one once and
    # keep it beside the database; sessions then survive restarts.
    key_file = DATA_DIR / "secret_key"
    if not key_file.exists():
        key_file.write_text(get_random_secret_key())
        key_file.chmod(0o600)
    return key_file.read_text().strip()


SECRET_KEY = _secret_key()
ALLOWED_HOSTS = env_list("FTT_ALLOWED_HOSTS", "127.0.0.1,localhost,[::1]")
CSRF_TRUSTED_ORIGINS = env_list("FTT_CSRF_TRUSTED_ORIGINS")

# Behind HTTPS (production) everything that can leak a session is locked down.
HTTPS = env_bool("FTT_HTTPS", False)
SESSION_COOKIE_SECURE = HTTPS
CSRF_COOKIE_SECURE = HTTPS
SECURE_SSL_REDIRECT = HTTPS and env_bool("FTT_SSL_REDIRECT", True)
SECURE_HSTS_SECONDS = env_int("FTT_HSTS_SECONDS", 31536000 if HTTPS else 0)
SECURE_HSTS_INCLUDE_SUBDOMAINS = HTTPS
SECURE_HSTS_PRELOAD = HTTPS
if env_bool("FTT_BEHIND_PROXY", False):
    SECURE_PROXY_SSL_HEADER = ("HTTP_X_FORWARDED_PROTO", "https")
SECURE_CONTENT_TYPE_NOSNIFF = True
SECURE_REFERRER_POLICY = "same-origin"
X_FRAME_OPTIONS = "DENY"

INSTALLED_APPS = [
    "daphne",
    "django.contrib.admin",
    "django.contrib.auth",
    "django.contrib.contenttypes",
    "django.contrib.sessions",
    "django.contrib.messages",
    "django.contrib.staticfiles",
    "django.contrib.gis",
    "rest_framework",
    "rest_framework.authtoken",
    "rest_framework_gis",
    "django_filters",
    "drf_spectacular",
    "drf_spectacular_sidecar",
    "corsheaders",
    "leaflet",
    "channels",
    "ftt_site",
    "events",
    "telemetry",
    "reports",
    "rosbridge_app",
    # Last, so it sees every FileField and deletes files with their rows.
    "django_cleanup.apps.CleanupConfig",
]

MIDDLEWARE = [
    "django.middleware.security.SecurityMiddleware",
    "whitenoise.middleware.WhiteNoiseMiddleware",
    "django.contrib.sessions.middleware.SessionMiddleware",
    "corsheaders.middleware.CorsMiddleware",
    "django.middleware.common.CommonMiddleware",
    "django.middleware.csrf.CsrfViewMiddleware",
    "django.contrib.auth.middleware.AuthenticationMiddleware",
    "django.contrib.messages.middleware.MessageMiddleware",
    "django.middleware.clickjacking.XFrameOptionsMiddleware",
]

ROOT_URLCONF = "ftt_site.urls"
WSGI_APPLICATION = "ftt_site.wsgi.application"
ASGI_APPLICATION = "ftt_site.asgi.application"

TEMPLATES = [
    {
        "BACKEND": "django.template.backends.django.DjangoTemplates",
        "DIRS": [BASE_DIR / "templates"],
        "APP_DIRS": True,
        "OPTIONS": {
            "context_processors": [
                "django.template.context_processors.request",
                "django.contrib.auth.context_processors.auth",
                "django.contrib.messages.context_processors.messages",
            ],
        },
    },
]


def _databases() -> dict:
    url = env_str("FTT_DATABASE_URL")
    if url:
        db = dj_database_url.parse(url, conn_max_age=env_int("FTT_DB_CONN_MAX_AGE", 60))
        if db["ENGINE"] == "django.db.backends.postgresql":
            db["ENGINE"] = "django.contrib.gis.db.backends.postgis"
        if db["ENGINE"] != "django.contrib.gis.db.backends.postgis":
            raise ValueError("FTT_DATABASE_URL must be a postgis:// or postgres:// URL")
        db["CONN_HEALTH_CHECKS"] = True
        return {"default": db}
    return {
        "default": {
            "ENGINE": "ftt_site.db_spatialite",
            "NAME": DATA_DIR / "ftt.sqlite3",
            # The collector writes from its own process: WAL lets readers go on
            # while it writes, IMMEDIATE takes the write lock at BEGIN so two
            # writers queue instead of failing half-way through a transaction.
            "OPTIONS": {
                "timeout": 30,
                "transaction_mode": "IMMEDIATE",
                "init_command": "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;",
            },
            "TEST": {"NAME": str(DATA_DIR / "test_ftt.sqlite3")},
        }
    }


DATABASES = _databases()
DEFAULT_AUTO_FIELD = "django.db.models.BigAutoField"

AUTH_PASSWORD_VALIDATORS = [
    {"NAME": "django.contrib.auth.password_validation.UserAttributeSimilarityValidator"},
    {"NAME": "django.contrib.auth.password_validation.MinimumLengthValidator"},
    {"NAME": "django.contrib.auth.password_validation.CommonPasswordValidator"},
    {"NAME": "django.contrib.auth.password_validation.NumericPasswordValidator"},
]

LANGUAGE_CODE = "en-us"
TIME_ZONE = env_str("FTT_TIME_ZONE", "UTC")
USE_I18N = True
USE_TZ = True

STATIC_URL = "static/"
STATIC_ROOT = DATA_DIR / "staticfiles"
# WhiteNoise warns on every start when the collectstatic target is missing.
STATIC_ROOT.mkdir(exist_ok=True)
STATICFILES_DIRS = [BASE_DIR / "static"]
MEDIA_URL = "media/"
MEDIA_ROOT = Path(env_str("FTT_MEDIA_ROOT", str(DATA_DIR / "media")))
STORAGES = {
    "default": {"BACKEND": "django.core.files.storage.FileSystemStorage"},
    "staticfiles": {"BACKEND": "whitenoise.storage.CompressedStaticFilesStorage"},
}
# Tests and the dev server run without collectstatic.
WHITENOISE_USE_FINDERS = True
WHITENOISE_AUTOREFRESH = DEBUG
FILE_UPLOAD_MAX_MEMORY_SIZE = 10 * 1024 * 1024
DATA_UPLOAD_MAX_MEMORY_SIZE = 50 * 1024 * 1024

LOGIN_URL = "login"
LOGIN_REDIRECT_URL = "/"
LOGOUT_REDIRECT_URL = "login"

REDIS_URL = env_str("FTT_REDIS_URL")
if REDIS_URL:
    CHANNEL_LAYERS = {
        "default": {
            "BACKEND": "channels_redis.pubsub.RedisPubSubChannelLayer",
            "CONFIG": {"hosts": [REDIS_URL]},
        }
    }
else:
    CHANNEL_LAYERS = {"default": {"BACKEND": "channels.layers.InMemoryChannelLayer"}}

CORS_ALLOWED_ORIGINS = env_list("FTT_CORS_ALLOWED_ORIGINS")
CORS_URLS_REGEX = r"^/api/.*$"

REST_FRAMEWORK = {
    "DEFAULT_AUTHENTICATION_CLASSES": [
        # Token first: an anonymous request then gets 401 with "WWW-Authenticate: Token".
        "rest_framework.authentication.TokenAuthentication",
        "rest_framework.authentication.SessionAuthentication",
    ],
    "DEFAULT_PERMISSION_CLASSES": ["events.api.permissions.RolePermission"],
    "DEFAULT_PAGINATION_CLASS": "events.api.pagination.Pagination",
    "PAGE_SIZE": 100,
    "DEFAULT_FILTER_BACKENDS": ["django_filters.rest_framework.DjangoFilterBackend"],
    "DEFAULT_SCHEMA_CLASS": "drf_spectacular.openapi.AutoSchema",
    "EXCEPTION_HANDLER": "events.api.errors.exception_handler",
    "DEFAULT_PARSER_CLASSES": [
        "events.api.parsers.JSONParser",
        "rest_framework.parsers.FormParser",
        "rest_framework.parsers.MultiPartParser",
    ],
    "TEST_REQUEST_DEFAULT_FORMAT": "json",
}
SPECTACULAR_SETTINGS = {
    "TITLE": "Field Test Tool API",
    "DESCRIPTION": "Test events, shifts, legs, segments and the robot data recorded in them.",
    "VERSION": "1.0.0",
    "SERVE_INCLUDE_SCHEMA": False,
    "COMPONENT_SPLIT_REQUEST": True,
    # Swagger UI from our own static files: the docs page works on a field without internet.
    "SWAGGER_UI_DIST": "SIDECAR",
    "SWAGGER_UI_FAVICON_HREF": "SIDECAR",
    "REDOC_DIST": "SIDECAR",
}

# GDAL < 3.9 (Debian 12 ships 3.6) cannot sandbox file access; FTT never
# opens rasters through GDAL, so the warning does not apply.
SILENCED_SYSTEM_CHECKS = ["gis.W001"]

LOGGING = {
    "version": 1,
    "disable_existing_loggers": False,
    "formatters": {"plain": {"format": "%(asctime)s %(levelname)s %(name)s: %(message)s"}},
    "handlers": {"console": {"class": "logging.StreamHandler", "formatter": "plain"}},
    "root": {"handlers": ["console"], "level": env_str("FTT_LOG_LEVEL", "INFO")},
    "loggers": {"django.db.backends": {"level": "WARNING"}},
}

# Tile server used by the GUI maps (site default, users may override it).
FTT_TILE_URL = env_str("FTT_TILE_URL", "https://tile.openstreetmap.org/{z}/{x}/{y}.png")
# PDF reports: where map tiles are cached, and how requested reports run
# ("thread" in the web process, or "subprocess": manage.py ftt_report --job ID).
FTT_TILE_CACHE = Path(env_str("FTT_TILE_CACHE", str(DATA_DIR / "tile_cache")))
FTT_REPORT_WORKER = env_str("FTT_REPORT_WORKER", "thread")
# Title-page logo of every report (PNG, JPEG or SVG); empty: FTT's own.
FTT_REPORT_LOGO = env_str("FTT_REPORT_LOGO", "")
# Behind nginx: the internal location that maps to MEDIA_ROOT. FTT still checks
# the role, then hands the file transfer to nginx (X-Accel-Redirect).
FTT_MEDIA_ACCEL_PREFIX = env_str("FTT_MEDIA_ACCEL_PREFIX", "")

# django-leaflet ships Leaflet itself, so admin map widgets work offline; only
# the tiles come from the network, and the widget still works without them.
LEAFLET_CONFIG = {
    "TILES": [("Map", FTT_TILE_URL, {"attribution": "&copy; OpenStreetMap contributors"})],
    "DEFAULT_CENTER": (50.0, 7.0),
    "DEFAULT_ZOOM": 3,
    "RESET_VIEW": False,
}
