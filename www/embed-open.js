// embed.html → index.html?embed with the same fragment (#d=…&fields=…): the embedded weft is
// the page in its embed mode (embed.js). Replaces the history entry, so Back leaves the frame.
location.replace(`index.html?embed${location.hash}`);
