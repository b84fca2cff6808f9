"""The page's language: the account's preference, else what LocaleMiddleware
took from the browser (Accept-Language or the language cookie)."""

from django.conf import settings
from django.http import HttpResponseBadRequest, HttpResponseRedirect
from django.utils import translation
from django.utils.http import url_has_allowed_host_and_scheme
from django.views.decorators.http import require_POST

from common.models import AccountPreference

# Per session [user id, language or ""], so the preference costs one query per sign-in.
SESSION_KEY = "ftt_language"
# A choice made before signing in (the sign-in page's picker); Django's login keeps
# the session's data, so the account takes it at its first request.
CHOSEN_KEY = "ftt_language_chosen"


def account_language(request) -> str:
    """The signed-in account's chosen language, or "" for none."""
    user = getattr(request, "user", None)
    if user is None or not user.is_authenticated or not hasattr(request, "session"):
        return ""
    kept = request.session.get(SESSION_KEY)
    if not (isinstance(kept, list) and len(kept) == 2 and kept[0] == user.pk):
        chosen = request.session.pop(CHOSEN_KEY, None)
        if chosen in dict(settings.LANGUAGES):
            keep_language(user, chosen)
            language = chosen
        else:
            language = (
                AccountPreference.objects.filter(user=user)
                .values_list("language", flat=True)
                .first()
            )
        kept = [user.pk, language or ""]
        request.session[SESSION_KEY] = kept
    return kept[1]


def keep_language(user, language: str) -> None:
    """Keeps ``language`` ("" for none) as the account's choice."""
    AccountPreference.objects.update_or_create(user=user, defaults={"language": language})


class AccountLanguageMiddleware:
    """After AuthenticationMiddleware: an account's preference outranks the browser."""

    def __init__(self, get_response):
        self.get_response = get_response

    def __call__(self, request):
        language = account_language(request)
        if language:
            translation.activate(language)
            request.LANGUAGE_CODE = language
        return self.get_response(request)


@require_POST
def choose_language(request):
    """The language picker: kept on the account when signed in, else in the cookie."""
    language = request.POST.get("language", "")
    if language and language not in dict(settings.LANGUAGES):
        return HttpResponseBadRequest("unknown language")
    target = request.POST.get("next", "/")
    if not url_has_allowed_host_and_scheme(target, {request.get_host()}, request.is_secure()):
        target = "/"
    if request.user.is_authenticated:
        keep_language(request.user, language)
        request.session[SESSION_KEY] = [request.user.pk, language]
    elif language:
        request.session[CHOSEN_KEY] = language
    response = HttpResponseRedirect(target)
    if language:
        response.set_cookie(settings.LANGUAGE_COOKIE_NAME, language, samesite="Lax")
    else:
        response.delete_cookie(settings.LANGUAGE_COOKIE_NAME)
    return response
