"""Knowledge: rule files → compiled r(L) → decisions.

``expr`` parses propositional expressions; ``rules`` loads and validates rule files;
``notation`` prints terms in the paper's notation; ``bdd`` holds the shared decision-diagram
manager and its algorithms; ``knowledge`` the compiled data; ``compiler`` builds it;
``analysis``, ``engine``, ``economy`` and ``tree`` are functions over it; ``base`` is the
``KnowledgeBase`` facade that joins them. Nothing here knows about fingers, geometry or grasps.
"""
