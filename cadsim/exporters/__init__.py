"""Exporters of cadsim datasets into the field's layouts (``cadsim export``): the OPV2V layout
(:mod:`.opv2v`) and KITTI detection labels (:mod:`.kitti`). Both read a dataset through
``cadsim.dataset`` (verified first) and what a view is made of through :mod:`.view_boxes`; both
write only under the output folder, which must be new or empty. Must not import matchers or
eval.
"""
