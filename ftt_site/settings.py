"""Django settings for FTT.

Everything that differs between a laptop on the test field and a production
server comes from ``FTT_*`` environment variables; README.md lists them.
"""

import ipaddress
import socket
from datetime import timedelta
from functools import reduce
from operator import or_
from pathlib import Path
from urllib.parse import urlsplit

from ftt_site.db_spatialite import sqlite_shim

sqlite_shim.install()

import dj_database_url  # noqa: E402
import xstatic.pkg.leaflet_markercluster as markercluster  # noqa: E402
from csp.constants import NONE, SELF, UNSAFE_INLINE  # noqa: E402
from django.core.management.utils import get_random_secret_key  # noqa: E402

from common.roles import ADMINISTRATOR, ORDER  # noqa: E402
from ftt_site.env import (  # noqa: E402
    env_bool,
    env_int,
    env_list,
    env_pairs,
    env_str,
    private_dir,
    private_file,
)

BASE_DIR = Path(__file__).resolve().parent.parent
DATA_DIR = Path(env_str("FTT_DATA_DIR", str(BASE_DIR / "data")))
# The database, the secret key and the media are for FTT's user only.
private_dir(DATA_DIR)

DEBUG = env_bool("FTT_DEBUG", False)


def _origin(url: str) -> str:
    parts = urlsplit(url)
    return f"{parts.scheme}://{parts.netloc}" if parts.netloc else SELF


def _secret_key() -> str:
    key = env_str("FTT_SECRET_KEY")
    if key:
        return key
    # An embedded install has nobody to invent a key, so we make one once and
    # keep it beside the database; sessions then survive restarts.
    key_file = DATA_DIR / "secret_key"
    private_file(key_file, get_random_secret_key())
    return key_file.read_text().strip()


SECRET_KEY = _secret_key()
# The key that seals this installation's reports (docs/report.md), and the seal
# keys of other installations whose reports this one verifies too.
REPORT_SEAL_KEY = env_str("FTT_REPORT_SEAL_KEY") or SECRET_KEY
TRUSTED_SEAL_KEYS = env_list("FTT_TRUSTED_SEAL_KEYS")
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
FTT_BEHIND_PROXY = env_bool("FTT_BEHIND_PROXY", False)
# The proxies whose forwarded headers are believed (ftt_site.inbound.proxies); nobody's
# without FTT_BEHIND_PROXY.
FTT_PROXY_NETWORKS = [
    ipaddress.ip_network(net, strict=False)
    for net in env_list("FTT_PROXY_ADDRESSES", "127.0.0.1/32,::1/128")
]
if FTT_BEHIND_PROXY:
    SECURE_PROXY_SSL_HEADER = ("HTTP_X_FORWARDED_PROTO", "https")
# A load balancer's health probes may come over plain HTTP.
SECURE_REDIRECT_EXEMPT = [r"^healthz$", r"^readyz$"]
SECURE_CONTENT_TYPE_NOSNIFF = True
SECURE_REFERRER_POLICY = "same-origin"
X_FRAME_OPTIONS = "DENY"

# No "daphne" app: FTT is served by Gunicorn + Uvicorn (scripts/run.sh, README),
# and the app would load Twisted into every process, the collector included
# (about a second of its start-up on an idle machine).
INSTALLED_APPS = [
    "ftt_site.admin_site.FttAdminConfig",
    "django.contrib.auth",
    "django.contrib.contenttypes",
    "django.contrib.sessions",
    "django.contrib.messages",
    "django.contrib.staticfiles",
    "django.contrib.gis",
    "rest_framework",
    "rest_framework.authtoken",
    # Not "rest_framework_gis": its fields and filters are imported where used, and
    # its AppConfig only maps GeoDjango fields for ModelSerializer, which every
    # geometry field of ours declares itself, while loading DRF's serializers
    # (and with them the HTTP client stack) into every process at start.
    "django_filters",
    "drf_spectacular",
    "drf_spectacular_sidecar",
    "corsheaders",
    "csp",
    "axes",
    "leaflet",
    "channels",
    "django_tasks",
    "django_tasks_db",
    "django_prometheus",
    "simple_history",
    "ftt_site",
    "common",
    "events",
    "telemetry",
    "basemaps",
    "reports",
    "rosbridge_app",
    "live",
    "exchange",
    "gui",
    # Last, so it sees every FileField and deletes files with their rows.
    "django_cleanup.apps.CleanupConfig",
]

MIDDLEWARE = [
    # Before anything reads the client's address or scheme (ftt_site.inbound.proxies).
    "ftt_site.inbound.proxies.ForwardedHeadersMiddleware",
    # First and last: request counts and latencies for /metrics (ftt_site.monitoring.metrics).
    "django_prometheus.middleware.PrometheusBeforeMiddleware",
    "django.middleware.security.SecurityMiddleware",
    "whitenoise.middleware.WhiteNoiseMiddleware",
    "django.contrib.sessions.middleware.SessionMiddleware",
    # The page's language: the account's preference (ftt_site.inbound.language), else the
    # browser's Accept-Language, else English.
    "django.middleware.locale.LocaleMiddleware",
    "corsheaders.middleware.CorsMiddleware",
    "django.middleware.common.CommonMiddleware",
    "django.middleware.csrf.CsrfViewMiddleware",
    "django.contrib.auth.middleware.AuthenticationMiddleware",
    "ftt_site.inbound.language.AccountLanguageMiddleware",
    "django.contrib.messages.middleware.MessageMiddleware",
    "django.middleware.clickjacking.XFrameOptionsMiddleware",
    "csp.middleware.CSPMiddleware",
    # Who changed a row and through what (events.history).
    "ftt_site.inbound.change_origin.ChangeOriginMiddleware",
    # Last: turns a lockout, or a directory that cannot be reached, on any login
    # path into one answer (ftt_site.inbound.lockout).
    "ftt_site.inbound.lockout.DirectoryUnavailableMiddleware",
    "axes.middleware.AxesMiddleware",
    "django_prometheus.middleware.PrometheusAfterMiddleware",
]

# Failed logins on every path (GUI, admin, /api/token/) are counted by
# django-axes (ftt_site.inbound.lockout): an address that fails too often is locked,
# whatever accounts it tried; an account failed from many addresses is only
# slowed down, so no stranger can lock someone else out.
AUTHENTICATION_BACKENDS = [
    "axes.backends.AxesStandaloneBackend",
    "ftt_site.inbound.lockout.AccountPace",
    "django.contrib.auth.backends.ModelBackend",
]
AXES_FAILURE_LIMIT = env_int("FTT_LOGIN_FAILURE_LIMIT", 5)
AXES_COOLOFF_TIME = timedelta(minutes=env_int("FTT_LOGIN_COOLOFF_MINUTES", 15))
AXES_LOCKOUT_PARAMETERS = ["ip_address"]
# An attempt refused while locked or slowed does not count as one more failure.
AXES_RESET_COOL_OFF_ON_FAILURE_DURING_LOCKOUT = False
FTT_LOGIN_ACCOUNT_PACE_SECONDS = env_int("FTT_LOGIN_ACCOUNT_PACE_SECONDS", 10)
# How long a web process keeps an API token (with its account's roles) and a
# robot account's vehicles after reading them (common.api.authentication).
FTT_TOKEN_CACHE_SECONDS = env_int("FTT_TOKEN_CACHE_SECONDS", 5)
# Statistics count the robot's suggested reason of a take-over nobody has
# annotated yet (params.reason_rules); off: confirmed reasons only.
FTT_COUNT_ROBOT_REASONS = env_bool("FTT_COUNT_ROBOT_REASONS", False)
# Stored poses of shifts older than this many months are thinned to what the
# report draws (reports.services.pose_retention); 0: all poses are kept.
FTT_POSE_RETENTION_MONTHS = env_int("FTT_POSE_RETENTION_MONTHS", 0)
# A sign-in forgives only its own account's failures from its address
# (ftt_site.inbound.lockout.forgive_own_failures), never another account's.
AXES_RESET_ON_SUCCESS = False
AXES_LOCKOUT_CALLABLE = "ftt_site.inbound.lockout.locked_out"
AXES_CLIENT_IP_CALLABLE = "ftt_site.inbound.lockout.client_address"

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
        # Under ASGI every request runs in a thread of its own, so a persistent
        # connection per thread grows with the load until PostgreSQL refuses
        # ("too many clients"). Instead each process keeps one psycopg pool of
        # FTT_DB_POOL_SIZE connections; a request waits up to FTT_DB_POOL_TIMEOUT
        # seconds for one, then gets 503 with Retry-After. README states the budget.
        pool_size = env_int("FTT_DB_POOL_SIZE", 8)
        db = dj_database_url.parse(
            url, conn_max_age=0 if pool_size else env_int("FTT_DB_CONN_MAX_AGE", 0)
        )
        if db["ENGINE"] == "django.db.backends.postgresql":
            db["ENGINE"] = "django.contrib.gis.db.backends.postgis"
        if db["ENGINE"] != "django.contrib.gis.db.backends.postgis":
            raise ValueError("FTT_DATABASE_URL must be a postgis:// or postgres:// URL")
        if pool_size:
            db.setdefault("OPTIONS", {})["pool"] = {
                "min_size": 1,
                "max_size": pool_size,
                "timeout": env_int("FTT_DB_POOL_TIMEOUT", 20),
            }
        else:
            db["CONN_HEALTH_CHECKS"] = True
        return {"default": db}
    private_file(DATA_DIR / "ftt.sqlite3")
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

# The language of pages whose browser asks for neither English nor German, of the
# collector's log and of the service messages outside a request.
LANGUAGE_CODE = env_str("FTT_LANGUAGE", "en")
# English and German; the catalogues are locale/<lang>/LC_MESSAGES/django.po and
# djangojs.po (README: "Translations"), compiled to .mo by scripts/setup.sh.
LANGUAGES = [("en", "English"), ("de", "Deutsch")]
LOCALE_PATHS = [BASE_DIR / "locale"]
TIME_ZONE = env_str("FTT_TIME_ZONE", "UTC")
USE_I18N = True
USE_TZ = True

STATIC_URL = "static/"
STATIC_ROOT = DATA_DIR / "staticfiles"
# WhiteNoise warns on every start when the collectstatic target is missing.
STATIC_ROOT.mkdir(exist_ok=True)
# Leaflet.markercluster from its PyPI package, served beside django-leaflet's Leaflet.
STATICFILES_DIRS = [BASE_DIR / "static", ("leaflet-markercluster", markercluster.BASE_DIR)]
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
# Checked by ftt_site.inbound.limits before a body is read: uploads of images,
# maps and archives may be large, for accounts that may upload them
# (ftt_site.inbound.uploaders); every other request takes small bodies only.
FTT_MAX_REQUEST_BODY = env_int("FTT_MAX_REQUEST_BODY", DATA_UPLOAD_MAX_MEMORY_SIZE)
FTT_MAX_UPLOAD_SIZE = env_int("FTT_MAX_UPLOAD_SIZE", 2 * 1024**3)
# A request's headers must arrive within FTT_HEADER_TIMEOUT seconds
# (ftt_site.server.web_worker); its body, after FTT_BODY_GRACE_SECONDS, at no less than
# FTT_BODY_MIN_RATE bytes per second on average, or it is answered 408.
FTT_HEADER_TIMEOUT = env_int("FTT_HEADER_TIMEOUT", 10)
FTT_BODY_GRACE_SECONDS = env_int("FTT_BODY_GRACE_SECONDS", 10)
FTT_BODY_MIN_RATE = env_int("FTT_BODY_MIN_RATE", 1024)
# Requests running in the application at once per web process (each is a
# thread, taken once the body has arrived); the rest wait up to
# FTT_REQUEST_QUEUE_TIMEOUT seconds, then 503.
FTT_MAX_ACTIVE_REQUESTS = env_int("FTT_MAX_ACTIVE_REQUESTS", 8)
FTT_REQUEST_QUEUE_TIMEOUT = env_int("FTT_REQUEST_QUEUE_TIMEOUT", 30)

LOGIN_URL = "login"
LOGIN_REDIRECT_URL = "/"
LOGOUT_REDIRECT_URL = "login"

REDIS_URL = env_str("FTT_REDIS_URL")
# How often a web process reads the change feed when no wake-up arrives (a
# commit normally wakes it at once: NOTIFY on PostgreSQL, Redis, or in-process).
FTT_LIVE_POLL_MS = env_int("FTT_LIVE_POLL_MS", 200)
# How often the server speaks on an open live websocket, so that a page can tell
# a quiet link from a dead one; the page shows its link stale after three missed.
FTT_LIVE_HEARTBEAT_MS = env_int("FTT_LIVE_HEARTBEAT_MS", 1000)
# Live links one account, and one client address, may hold open per web process
# (live.consumers); more are closed with code 4429.
FTT_LIVE_LINKS_PER_ACCOUNT = env_int("FTT_LIVE_LINKS_PER_ACCOUNT", 20)
FTT_LIVE_LINKS_PER_ADDRESS = env_int("FTT_LIVE_LINKS_PER_ADDRESS", 60)
# Each process sends the cross-process wake-ups (NOTIFY, Redis) from a thread of
# its own, at most once per this long (live.wakeup).
FTT_LIVE_NOTIFY_DELAY_MS = env_int("FTT_LIVE_NOTIFY_DELAY_MS", 2)
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
        "common.api.authentication.TokenAuthentication",
        "rest_framework.authentication.SessionAuthentication",
    ],
    "DEFAULT_PERMISSION_CLASSES": ["common.api.permissions.RolePermission"],
    "DEFAULT_PAGINATION_CLASS": "common.api.pagination.Pagination",
    "PAGE_SIZE": 100,
    # django-filter's, refusing a parameter the list does not know.
    "DEFAULT_FILTER_BACKENDS": ["events.api.filters.SearchFilterBackend"],
    "DEFAULT_SCHEMA_CLASS": "drf_spectacular.openapi.AutoSchema",
    "EXCEPTION_HANDLER": "common.api.errors.exception_handler",
    "DEFAULT_PARSER_CLASSES": [
        "common.api.parsers.JSONParser",
        "rest_framework.parsers.FormParser",
        "rest_framework.parsers.MultiPartParser",
    ],
    "TEST_REQUEST_DEFAULT_FORMAT": "json",
    # Beyond this a client gets 429 with Retry-After; a robot batches its points
    # and stays far below.
    "DEFAULT_THROTTLE_CLASSES": [
        "rest_framework.throttling.AnonRateThrottle",
        "rest_framework.throttling.UserRateThrottle",
    ],
    # REMOTE_ADDR, the client's address by ftt_site.inbound.proxies' rule.
    "NUM_PROXIES": 0,
    "DEFAULT_THROTTLE_RATES": {
        "anon": env_str("FTT_API_RATE_ANON", "120/min"),
        "user": env_str("FTT_API_RATE_USER", "3000/min"),
    },
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
    # No robot token from a /legacy/ path in any line (ftt_site.inbound.log_masks).
    "filters": {"robot_tokens": {"()": "ftt_site.inbound.log_masks.MaskRobotTokens"}},
    "handlers": {
        "console": {
            "class": "logging.StreamHandler",
            "formatter": "plain",
            "filters": ["robot_tokens"],
        }
    },
    "root": {"handlers": ["console"], "level": env_str("FTT_LOG_LEVEL", "INFO")},
    "loggers": {"django.db.backends": {"level": "WARNING"}},
}

# Tile server used by the GUI maps (site default, users may override it).
FTT_TILE_URL = env_str("FTT_TILE_URL", "https://tile.openstreetmap.org/{z}/{x}/{y}.png")
# Tile servers an external basemap layer may name (basemaps.hosts): names, or
# "*.domain" for the names below it; IP addresses only listed exactly.
FTT_TILE_HOSTS = env_list("FTT_TILE_HOSTS", urlsplit(FTT_TILE_URL).hostname or "")
# PDF reports: where map tiles are cached.
FTT_TILE_CACHE = Path(env_str("FTT_TILE_CACHE", str(DATA_DIR / "tile_cache")))
# Basemaps (docs/basemaps.md): largest file an administrator may upload, and how
# many tiles per second ``ftt_basemap fetch`` asks of a tile server.
FTT_BASEMAP_MAX_UPLOAD_MB = env_int("FTT_BASEMAP_MAX_UPLOAD_MB", 2048)
FTT_BASEMAP_FETCH_RATE = float(env_str("FTT_BASEMAP_FETCH_RATE", "2"))
# Seconds an MBTiles archive may take to give one tile before the tile is
# answered 503 (basemaps.mbtiles).
FTT_TILE_SECONDS = float(env_str("FTT_TILE_SECONDS", "2"))
# Background jobs (reports, archive imports) wait in FTT's own database until
# ``manage.py ftt_worker`` runs them (common/jobs.py says why this queue).
# Reports one account may have queued or running at once; more are 429.
FTT_MAX_WAITING_REPORTS = env_int("FTT_MAX_WAITING_REPORTS", 5)
TASKS = {"default": {"BACKEND": "django_tasks_db.DatabaseBackend", "QUEUES": ["default"]}}
# Title-page logo of every report (PNG, JPEG or SVG); empty: FTT's own.
FTT_REPORT_LOGO = env_str("FTT_REPORT_LOGO", "")
# Behind nginx: the internal location that maps to MEDIA_ROOT. FTT still checks
# the role, then hands the file transfer to nginx (X-Accel-Redirect).
FTT_MEDIA_ACCEL_PREFIX = env_str("FTT_MEDIA_ACCEL_PREFIX", "")
# Against decompression bombs: photos and maps with more pixels are refused.
FTT_MAX_IMAGE_PIXELS = env_int("FTT_MAX_IMAGE_PIXELS", 40_000_000)
# Archive import limits, checked while a member is decompressed (zip bombs).
FTT_ARCHIVE_MAX_MEMBERS = env_int("FTT_ARCHIVE_MAX_MEMBERS", 100_000)
FTT_ARCHIVE_MAX_MEMBER_BYTES = env_int("FTT_ARCHIVE_MAX_MEMBER_BYTES", 2 * 1024**3)
FTT_ARCHIVE_MAX_TOTAL_BYTES = env_int("FTT_ARCHIVE_MAX_TOTAL_BYTES", 20 * 1024**3)
FTT_ARCHIVE_MAX_RATIO = env_int("FTT_ARCHIVE_MAX_RATIO", 200)
FTT_ARCHIVE_MAX_FILE_BYTES = env_int("FTT_ARCHIVE_MAX_FILE_BYTES", 256 * 1024**2)
# This installation's name in the archives it writes: the history another
# installation imports from them says it was recorded here.
FTT_INSTALLATION_NAME = env_str("FTT_INSTALLATION_NAME", socket.gethostname())[:150]
# How far ahead of the importing machine's clock an imported history entry
# may be dated before it is refused as lying in the future.
FTT_IMPORT_CLOCK_TOLERANCE = env_int("FTT_IMPORT_CLOCK_TOLERANCE", 300)

# Content-Security-Policy (django-csp) on every page: GUI, admin, API docs.
# Scripts only from FTT's own static files, so a stored script never runs;
# styles may be inline (Leaflet and the admin set style attributes); pictures
# also from the tile server and any https tile server an operator picks.
CONTENT_SECURITY_POLICY = {
    "DIRECTIVES": {
        "default-src": [SELF],
        "script-src": [SELF],
        "style-src": [SELF, UNSAFE_INLINE],
        "img-src": [SELF, "data:", "blob:", "https:", _origin(FTT_TILE_URL)],
        "connect-src": [SELF],
        "font-src": [SELF],
        "object-src": [NONE],
        "base-uri": [SELF],
        "form-action": [SELF],
        "frame-ancestors": [NONE],
    }
}

# django-leaflet ships Leaflet itself, so admin map widgets work offline; only
# the tiles come from the network, and the widget still works without them.
LEAFLET_CONFIG = {
    "TILES": [("Map", FTT_TILE_URL, {"attribution": "&copy; OpenStreetMap contributors"})],
    "DEFAULT_CENTER": (50.0, 7.0),
    "DEFAULT_ZOOM": 3,
    "RESET_VIEW": False,
}

# Monitoring (README, Monitoring): who may read /metrics (a bearer token, or a
# client address in these networks), and the free disk below which /readyz
# answers 503.
FTT_METRICS_TOKEN = env_str("FTT_METRICS_TOKEN", "")
FTT_METRICS_NETWORKS = [
    ipaddress.ip_network(net, strict=False)
    for net in env_list("FTT_METRICS_ADDRESSES", "127.0.0.1/32,::1/128")
]
FTT_READY_MIN_FREE_MB = env_int("FTT_READY_MIN_FREE_MB", 1024)
# The migrations' state is read by /readyz, not at every start.
PROMETHEUS_EXPORT_MIGRATIONS = False

# Sign-in from a directory (README, Directory sign-in): with FTT_LDAP_SERVER_URI
# set, django-auth-ldap checks passwords against LDAP or Active Directory after
# the local accounts, for names that are none; a directory user gets the FTT
# role of the highest role group they are in (common.directory), and one in
# none of them is refused.
FTT_LDAP_ROLE_GROUPS = {
    role: env_str(f"FTT_LDAP_{role.upper()}_GROUP")
    for role in ORDER
    if env_str(f"FTT_LDAP_{role.upper()}_GROUP")
}
if env_str("FTT_LDAP_SERVER_URI"):
    # The LDAP client library is loaded only where a directory is configured.
    import ldap
    from django_auth_ldap.config import (
        GroupOfNamesType,
        LDAPGroupQuery,
        LDAPSearch,
        NestedActiveDirectoryGroupType,
    )

    if not FTT_LDAP_ROLE_GROUPS:
        raise ValueError(
            "FTT_LDAP_SERVER_URI needs FTT_LDAP_VIEWER_GROUP, FTT_LDAP_OPERATOR_GROUP "
            "or FTT_LDAP_ADMINISTRATOR_GROUP: directory users without a role cannot sign in"
        )
    # After the local accounts, and never for their names (common.directory).
    AUTHENTICATION_BACKENDS.append("common.directory.DirectoryBackend")
    # Seconds the directory may take to connect and to answer each request; a
    # directory that did not is asked again after as long (common.directory).
    FTT_LDAP_TIMEOUT = env_int("FTT_LDAP_TIMEOUT", 5)
    # Sign-ins per web process that may wait for the directory at once.
    FTT_LDAP_MAX_SIGN_INS = env_int("FTT_LDAP_MAX_SIGN_INS", 2)
    # Seconds between two role checks of one directory account, at its use and
    # on the worker's schedule (common.directory.recheck_role; docs/accounts.md).
    FTT_LDAP_RECHECK_SECONDS = env_int("FTT_LDAP_RECHECK_SECONDS", 300)
    AUTH_LDAP_CONNECTION_OPTIONS = {
        ldap.OPT_NETWORK_TIMEOUT: FTT_LDAP_TIMEOUT,
        ldap.OPT_TIMEOUT: FTT_LDAP_TIMEOUT,
    }
    AUTH_LDAP_SERVER_URI = env_str("FTT_LDAP_SERVER_URI")
    AUTH_LDAP_START_TLS = env_bool("FTT_LDAP_START_TLS", False)
    AUTH_LDAP_BIND_DN = env_str("FTT_LDAP_BIND_DN")
    AUTH_LDAP_BIND_PASSWORD = env_str("FTT_LDAP_BIND_PASSWORD")
    AUTH_LDAP_USER_SEARCH = LDAPSearch(
        env_str("FTT_LDAP_USER_BASE"),
        ldap.SCOPE_SUBTREE,
        env_str("FTT_LDAP_USER_FILTER", "(uid=%(user)s)"),
    )
    AUTH_LDAP_GROUP_SEARCH = LDAPSearch(
        env_str("FTT_LDAP_GROUP_BASE", env_str("FTT_LDAP_USER_BASE")), ldap.SCOPE_SUBTREE
    )
    AUTH_LDAP_GROUP_TYPE = (
        NestedActiveDirectoryGroupType()
        if env_str("FTT_LDAP_GROUP_TYPE", "groupOfNames") == "active_directory"
        else GroupOfNamesType()
    )
    AUTH_LDAP_USER_ATTR_MAP = {"first_name": "givenName", "last_name": "sn", "email": "mail"}
    AUTH_LDAP_REQUIRE_GROUP = reduce(or_, map(LDAPGroupQuery, FTT_LDAP_ROLE_GROUPS.values()))
    if env_str("FTT_LDAP_DENY_GROUP"):
        AUTH_LDAP_DENY_GROUP = env_str("FTT_LDAP_DENY_GROUP")
    if ADMINISTRATOR in FTT_LDAP_ROLE_GROUPS:
        AUTH_LDAP_USER_FLAGS_BY_GROUP = {"is_staff": FTT_LDAP_ROLE_GROUPS[ADMINISTRATOR]}
    AUTH_LDAP_CACHE_TIMEOUT = 300

# Change history (events.models.changes): a file field is kept as its name, so
# deleting an old history row never deletes a file (django-cleanup).
SIMPLE_HISTORY_FILEFIELD_TO_CHARFIELD = True

# Suggestions for a take-over's location type (free text; docs/report.md, DMV CSV).
FTT_LOCATION_TYPES = env_list("FTT_LOCATION_TYPES", "field,road,yard")
# The disengagement report's manufacturer and permit columns (ftt_report --dmv).
FTT_DMV_MANUFACTURER = env_str("FTT_DMV_MANUFACTURER", "")
FTT_DMV_PERMIT = env_str("FTT_DMV_PERMIT", "")
# FTT's words as the DMV form's (docs/report.md; checked at start by
# reports.checks): initiators, location types (any other: the default) and
# the vehicles capable of operating without a driver (their keys).
FTT_DMV_INITIATORS = env_pairs(
    "FTT_DMV_INITIATORS",
    "autonomous_system=AV System,safety_driver=Test Driver,"
    "remote_operator=Remote Operator,other=Passenger",
)
FTT_DMV_LOCATIONS = env_pairs(
    "FTT_DMV_LOCATIONS", "road=Street,field=Rural Road,yard=Parking Facility"
)
FTT_DMV_LOCATION_DEFAULT = env_str("FTT_DMV_LOCATION_DEFAULT", "Street")
FTT_DMV_DRIVERLESS_VEHICLES = env_list("FTT_DMV_DRIVERLESS_VEHICLES", "")
