"""Typed-value fields committed on Enter or on leaving the field, never keystroke by keystroke.

viser's number boxes send every keystroke, so typing ``-300`` applied ``-3`` and ``-30`` on the
way, and a refused value had already changed the state.  A :class:`TypedField` is a text box in
its own form; :data:`COMMIT_ON_BLUR_HTML` (added once to the page) keeps its keystrokes in the
browser's box (the page's handlers, and so the server, never see an intermediate state), and on
Enter or on leaving the field hands the box's whole text to the page once and submits the form;
the server acts only on that submit.  While a box has focus and holds typed text, a value pushed
by the server does not overwrite it.  On a refusal the box is put back to the value in force.

Why not per keystroke: the page sends GUI messages through one 50 ms throttle that keeps only
the latest message, so the form's "dirty" notice sent after a fast keystroke replaced that
keystroke's value update (``70`` typed without delay arrived as ``7``).

The same snippet hides the number boxes beside viser's sliders: sliders are for dragging,
typed values go through the fields.
"""

from __future__ import annotations

import time

__all__ = ["TypedField", "COMMIT_ON_BLUR_HTML", "SETTLE_S"]

SETTLE_S = 0.2
"""Seconds a submit waits for the field's value update sent just before it (runs in viser's callback thread)."""

_JS = (
    "if(!window.__armguardBlur){window.__armguardBlur=1;var pass=false;"
    "var isField=function(t){return !!(t&&t.tagName==='INPUT'&&t.dataset&&t.dataset.armguardField);};"
    "var field=function(t){return isField(t)&&t.closest?t.closest('form'):null;};"
    # keystrokes stay in the box: the page's own handlers (and so the server) never see them
    "var hold=function(e){if(!pass&&isField(e.target)){e.target.__agTyped=true;e.stopImmediatePropagation();}};"
    "document.addEventListener('input',hold,true);document.addEventListener('change',hold,true);"
    # on Enter / blur: hand the box's whole text to the page once, then submit its form
    "var proto=Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value');"
    "var commit=function(t){var f=field(t);if(!f)return;t.__agTyped=false;proto.set.call(t,t.value);pass=true;"
    "try{t.dispatchEvent(new Event('input',{bubbles:true}));}finally{pass=false;}"
    "setTimeout(function(){if(f.requestSubmit)f.requestSubmit();},150);};"
    "document.addEventListener('keydown',function(e){if(e.key!=='Enter'||!isField(e.target))return;"
    "e.preventDefault();e.stopPropagation();commit(e.target);},true);"
    "document.addEventListener('focusout',function(e){if(isField(e.target))commit(e.target);},true);"
    # a value pushed by the server never overwrites what is being typed in the focused box
    "var guard=function(i){var d=Object.getOwnPropertyDescriptor(i,'value')||proto;"
    "Object.defineProperty(i,'value',{configurable:true,get:function(){return d.get.call(i);},"
    "set:function(v){if(i.__agTyped&&document.activeElement===i)return;d.set.call(i,v);}});};"
    "var mark=function(){document.querySelectorAll('form input:not([type]),form input[type=text]').forEach(function(i){"
    "if(!i.dataset.armguardField){i.dataset.armguardField='1';guard(i);}});};"
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
