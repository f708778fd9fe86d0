// A classic script (browsers run these from file://, unlike modules): opened from a file, the
// page marks itself so that style.css shows only the note on how to serve it.
if (location.protocol === 'file:') document.documentElement.classList.add('from-file');
