-- A pandoc Lua filter for the notebooks sphinx-gallery writes (docs/conf.py, "pypandoc"):
-- pandoc reads a Sphinx role such as :class:`fempipe.PipeModel` as code carrying a "role"
-- attribute, which its Markdown writer prints as `fempipe.PipeModel`{.interpreted-text
-- role="class"}.  Here a code role (class, func, mod, meth, attr, ...) stays code, without
-- the attribute and without a leading "~"; a cross-reference with a title, such as
-- :doc:`Variants of the pipe </theory/variants>`, becomes its title as plain text (the
-- target is a page of the site, which a notebook cannot link to).
function Code(el)
  local role = el.attributes["role"]
  if role == nil then
    return nil
  end
  local title = el.text:match("^(.-)%s*<[^>]*>$")
  if role == "doc" or role == "ref" or role == "term" then
    return pandoc.Str(title or el.text)
  end
  local text = (title or el.text):gsub("^~", "")
  return pandoc.Code(text)
end
