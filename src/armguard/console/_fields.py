"""Typed-value fields committed on Enter or on leaving the field, never keystroke by keystroke.

viser's number boxes send every keystroke, so typing ``-300`` applied ``-3`` and ``-30`` on the
way, and a refused value had already changed the state.  A :class:`TypedField` is a text box in
its own form: the server keeps what is typed as text and only acts on the form's submit, which
the browser sends on Enter; :data:`COMMIT_ON_BLUR_HTML` (added once to the page) also submits a
field's form when focus leaves it.  On a refusal the box is put back to the value in force.

The same snippet hides the number boxes beside viser's sliders: sliders are for dragging,
typed values go through the fields.
"""

from __future__ import annotations

import time

__all__ = ["TypedField", "COMMIT_ON_BLUR_HTML", "SETTLE_S"]

SETTLE_S = 0.3
"""Seconds a submit waits for the field's last value update (runs in viser's callback thread)."""

_JS = (
    "if(!window.__armguardBlur){window.__armguardBlur=1;"
    "var field=function(t){if(!t||t.tagName!=='INPUT'||!t.closest||!t.dataset.armguardField)return null;"
    "return t.closest('form');};"
    # the submit goes after the last keystroke's value update has reached the server
    "var later=function(f){setTimeout(function(){if(f.requestSubmit)f.requestSubmit();},250);};"
    "document.addEventListener('keydown',function(e){if(e.key!=='Enter')return;var f=field(e.target);"
    "if(!f)return;e.preventDefault();e.stopPropagation();later(f);},true);"
    "document.addEventListener('focusout',function(e){var f=field(e.target);if(f&&e.relatedTarget)later(f);},true);"
    "var mark=function(){document.querySelectorAll('form input[type=text]').forEach(function(i){"
    "if(!i.dataset.armguardField)i.dataset.armguardField='1';});};"
    "new MutationObserver(mark).observe(document.body,{childList:true,subtree:true});mark();}"
)

COMMIT_ON_BLUR_HTML = (
    "<style>.mantine-Slider-root + .mantine-NumberInput-root{display:none !important}</style>"
    f'<img src="data:," alt="" style="display:none" onerror="{_JS}">'
)
"""HTML for ``gui.add_html``: submits a typed field's form on blur; hides sliders' number boxes."""


class TypedField:
    """A text field for one value: ``on_commit(text)`` runs on Enter or blur, with the typed text.

    ``shown`` is the text the box shows for the value in force; :meth:`show` updates it (only
    when it changed, so a refresh never overwrites what is being typed) and :meth:`revert` puts
    the box back to it after a refusal.
    """

    def __init__(self, gui, label: str, text: str, on_commit, *, hint: str | None = None) -> None:
        self.label = label
        self.shown = text
        with gui.add_form(None) as form:
            self.handle = gui.add_text(label, text, hint=hint)
        self.form = form

        def submit(event) -> None:
            if event.client is None:
                return
            # the browser may send the last keystroke's value just after the submit: let it land
            time.sleep(SETTLE_S)
            typed = str(self.handle.value)
            if typed.strip() == self.shown.strip():
                return  # Enter then blur, or a blur without an edit: nothing new
            on_commit(typed)

        form.on_submit(submit)

    def show(self, text: str) -> None:
        if text != self.shown:
            self.shown = text
            self.handle.value = text

    def revert(self) -> None:
        self.handle.value = self.shown
